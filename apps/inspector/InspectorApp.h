#pragma once
// loom-inspector: a render graph running live in a window. Graph view (passes, ports, edges),
// parameter widgets from the pass declarations, a texture viewer for any port, per-pass GPU
// timings, per-resource memory, camera controls, hot reload of shaders and the graph file, JSON
// save and Lua.
#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "apps/inspector/CameraController.h"
#include "apps/inspector/GraphFile.h"
#include "apps/inspector/GraphLayout.h"
#include "apps/inspector/Presenter.h"
#include "apps/inspector/TextureView.h"
#include "core/graph/Renderer.h"

namespace loom::inspector {

class InspectorApp {
public:
    struct Options {
        std::string graph, scene, script;
        std::map<std::string, std::string> sceneDefines;
        uint32_t width = 256, height = 256, seed = 0;
        int windowWidth = 1280, windowHeight = 800;
        uint32_t frames = 0;     // > 0: render this many frames, then exit
        std::string screenshot;  // with frames: write the whole window here before exiting
        std::string view;        // PASS.PORT shown first ("" = the first marked output)
        std::string select;      // pass whose parameters show first ("" = first pass)
        std::string device;
        bool validation = false;
    };
    explicit InspectorApp(Options options);
    ~InspectorApp();
    // Runs until the window closes (or --frames are done). Returns the exit code.
    int run();

private:
    enum class Severity { Info, Warning, Error };
    void log(Severity s, const std::string& text);
    void renderFrame();
    void pollHotReload();
    void setGraph(std::unique_ptr<RenderGraph> graph, const std::string& why);
    void refreshView();
    void resetCamera();
    void runScript();

    void drawUi();
    void drawMenuBar();
    void drawGraphView();
    void drawParameters();
    void drawTextureViewer();
    void drawTimings();
    void drawMemory();
    void drawCamera();
    void drawScript();
    void drawLog();
    void handleCameraInput(bool hovered);

    Options mOptions;
    std::shared_ptr<gpu::Context> mGpu;
    std::unique_ptr<Presenter> mPresenter;
    std::unique_ptr<Renderer> mRenderer;
    GraphLayout mLayout;
    std::string mSelectedPass, mViewPort;

    // Frame state.
    bool mPaused = false, mStep = false, mFrameFailed = false;
    uint64_t mFramesDone = 0;
    bool mNewFrame = false;
    std::deque<float> mFrameMs, mGpuMs;  // history, newest last
    double mLastFrameMs = 0.0;

    // Texture viewer.
    ViewSettings mViewSettings;
    DisplayTexture mDisplay;
    ImageData mViewImage;     // host copy of the viewed port
    std::string mViewStatus;  // why nothing is shown ("" when something is)
    bool mViewDirty = true;
    bool mFit = true;
    float mZoom = 1.0f;
    ImVec2 mPan{0.0f, 0.0f};  // image-space offset of the view centre from the image centre
    bool mNavigateCamera = false;
    std::string mSavePath = "out/inspector_view.exr";

    // Camera.
    CameraController mCamera;
    std::optional<scene::Camera> mSceneCamera;  // as loaded, with its path
    bool mFlyMode = false, mPlayPath = false, mCameraMoved = false;
    float mFlySpeed = 0.5f;  // scene radii per second

    // Hot reload.
    FileWatcher mGraphWatcher;
    std::chrono::steady_clock::time_point mLastPoll{};

    // Save, script, log.
    std::string mGraphSavePath;
    std::string mScriptPath, mScriptArgs, mScriptOutput;
    std::map<std::string, std::string> mTextEdits;  // "pass.param" -> text being edited
    struct Message {
        Severity severity;
        std::string text;
    };
    std::vector<Message> mMessages;
    std::string mLastError;
};

}  // namespace loom::inspector
