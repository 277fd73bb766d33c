#pragma once
// A graph bound to a GPU context and a frame size, driven frame by frame. The CLI, Lua and
// the inspector all render through this class.
#include <map>
#include <memory>
#include <string>

#include "core/graph/RenderGraph.h"
#include "core/image/Image.h"

namespace loom::scene {
class SceneGpu;
struct Scene;
}  // namespace loom::scene

namespace loom {

// PREFIX/share/loom when this executable is an installed PREFIX/bin one, else "".
std::string installedDataDir();
// Where shaders/, graphs/, scripts/ and scenes/ are: installedDataDir(), else the source tree
// this build came from, else "".
std::string dataRoot();
// Directories shaders are searched in: $LOOM_SHADER_PATH (colon-separated), then the installed
// PREFIX/share/loom/shaders, or in a build tree the source tree's shaders/.
std::vector<std::string> defaultShaderPaths();

class Renderer {
public:
    struct Options {
        std::string graph;  // path to graph JSON
        std::string scene;  // scene file (.json, .xml, .gltf/.glb, .obj); "" = none
        std::map<std::string, std::string> sceneDefines;  // Mitsuba $variables (-D)
        uint32_t width = 256, height = 256;
        uint32_t seed = 0;
        std::string device;
        std::string cacheDir;  // "" = default
        bool validation = false;
    };
    explicit Renderer(const Options& options);
    ~Renderer();
    // Use an existing context (tests share one).
    Renderer(std::shared_ptr<gpu::Context> gpu, std::unique_ptr<RenderGraph> graph, uint32_t width,
             uint32_t height, uint32_t seed = 0, std::string cacheDir = "");

    void frame();
    void frames(uint32_t n) {
        for (uint32_t i = 0; i < n; ++i) frame();
    }
    void resize(uint32_t width, uint32_t height);
    // Restart accumulation and history (bumps the external revision).
    void reset();
    void setSeed(uint32_t seed) { mSeed = seed; }
    // Loads a scene (replacing any previous one); its camera drives the frames.
    void loadScene(const std::string& path, const std::map<std::string, std::string>& defines = {});
    void setScene(scene::Scene scene);
    scene::SceneGpu* scene() { return mScene.get(); }
    // Animation time in frames (camera paths); constant unless the application steps it.
    void setTime(float time) { mTime = time; }
    float time() const { return mTime; }
    // Kernels compiled for the scene's material and light types only (default; the
    // environment's LOOM_SCENE_SPECIALIZATION=0 turns it off): off, they carry every type's
    // code, as kernels compiled without a scene do. Same images either way.
    void setSceneSpecialization(bool on) { mSceneSpecialization = on; }

    ImageData readOutput(const std::string& port);
    // Throws UserError when any float output holds NaN/Inf (names pass.port and pixel).
    void checkNaN();

    RenderGraph& graph() { return *mGraph; }
    // Swaps in another graph (inspector hot reload) and returns the previous one, so a caller
    // can swap it back when the new one fails to run.
    std::unique_ptr<RenderGraph> setGraph(std::unique_ptr<RenderGraph> graph);
    gpu::Context& gpu() { return *mGpu; }
    ShaderLibrary& shaders() { return *mShaders; }
    uint32_t width() const { return mWidth; }
    uint32_t height() const { return mHeight; }
    uint32_t seed() const { return mSeed; }
    uint64_t framesRendered() const { return mFrames; }

private:
    std::shared_ptr<gpu::Context> mGpu;
    std::unique_ptr<ShaderCompiler> mCompiler;
    std::unique_ptr<ShaderLibrary> mShaders;
    std::unique_ptr<RenderGraph> mGraph;
    std::unique_ptr<scene::SceneGpu> mScene;
    float mTime = 0.0f;
    uint32_t mWidth, mHeight, mSeed;
    uint64_t mExternalRevision = 0;
    uint64_t mFrames = 0;
    // The scene's defines among the compiler's (LOOM_SHAPE_MOTION_BLUR, LOOM_SCENE_MATERIALS,
    // LOOM_SCENE_LIGHTS), and whether the material and light types are specialised.
    ShaderDefines mSceneDefines;
    bool mSceneSpecialization = sceneSpecializationDefault();
    static bool sceneSpecializationDefault();
};

}  // namespace loom
