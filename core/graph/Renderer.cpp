#include "core/graph/Renderer.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "core/scene/SceneGpu.h"
#include "core/scene/SceneLoader.h"
#include "core/util/Log.h"

#ifndef LOOM_SOURCE_DIR
#define LOOM_SOURCE_DIR ""
#endif

namespace loom {

namespace fs = std::filesystem;

std::string installedDataDir() {
    std::error_code ec;
    auto exe = fs::read_symlink("/proc/self/exe", ec);
    if (ec) return "";
    auto share = exe.parent_path().parent_path() / "share/loom";
    return fs::exists(share / "shaders") ? share.string() : "";
}

std::string dataRoot() {
    // An installed loom (PREFIX/bin/loom next to PREFIX/share/loom) uses its own copy only, so
    // it behaves the same whether or not the source tree it was built from still exists.
    std::string root = installedDataDir();
    if (root.empty() && fs::exists(std::string(LOOM_SOURCE_DIR) + "/shaders"))
        root = LOOM_SOURCE_DIR;
    return root;
}

std::vector<std::string> defaultShaderPaths() {
    std::vector<std::string> paths;
    if (const char* env = std::getenv("LOOM_SHADER_PATH")) {
        std::stringstream ss(env);
        std::string p;
        while (std::getline(ss, p, ':'))
            if (!p.empty()) paths.push_back(p);
    }
    std::string root = dataRoot();
    if (!root.empty()) {
        paths.push_back(root + "/shaders");
        paths.push_back(root);  // lets graphs name "shaders/..." or "tests/data/..."
    }
    return paths;
}

Renderer::Renderer(const Options& o) : mWidth(o.width), mHeight(o.height), mSeed(o.seed) {
    gpu::Context::Options go;
    go.device = o.device;
    go.validation = o.validation;
    go.cacheDir = o.cacheDir;
    mGraph = RenderGraph::load(o.graph);  // parse before starting the device: fast errors
    mGpu = gpu::Context::create(go);
    mCompiler = std::make_unique<ShaderCompiler>(defaultShaderPaths(), mGpu->cacheDir());
    mCompiler->addSearchPath(mGraph->sourceDir());
    mShaders = std::make_unique<ShaderLibrary>(*mGpu, *mCompiler);
    if (!o.scene.empty()) loadScene(o.scene, o.sceneDefines);
}

Renderer::~Renderer() = default;

bool Renderer::sceneSpecializationDefault() {
    const char* e = std::getenv("LOOM_SCENE_SPECIALIZATION");
    return !(e && std::string(e) == "0");
}

void Renderer::loadScene(const std::string& path,
                         const std::map<std::string, std::string>& defines) {
    scene::SceneLoadOptions options;
    options.defines = defines;
    setScene(scene::loadScene(path, options));
}

void Renderer::setScene(scene::Scene s) {
    mScene = std::make_unique<scene::SceneGpu>(*mGpu, std::move(s));
    ++mExternalRevision;
}

Renderer::Renderer(std::shared_ptr<gpu::Context> gpu, std::unique_ptr<RenderGraph> graph,
                   uint32_t width, uint32_t height, uint32_t seed, std::string cacheDir)
    : mGpu(std::move(gpu)), mGraph(std::move(graph)), mWidth(width), mHeight(height), mSeed(seed) {
    mCompiler = std::make_unique<ShaderCompiler>(defaultShaderPaths(),
                                                 cacheDir.empty() ? mGpu->cacheDir() : cacheDir);
    mCompiler->addSearchPath(mGraph->sourceDir());
    mShaders = std::make_unique<ShaderLibrary>(*mGpu, *mCompiler);
}

void Renderer::frame() {
    FrameInputs in;
    in.seed = mSeed;
    in.externalRevision = mExternalRevision;
    in.time = mTime;
    if (mScene) {
        mScene->setFrame(mTime, mWidth, mHeight);
        // Kernels are compiled for what the scene has: the motion-blur code of moving shapes
        // only while shapes move over the shutter (it costs static traversal about 13 % on
        // lavapipe), and only the material types, light types and texture slots the scene
        // uses (llvmpipe runs every if-block's code whether a lane takes it or not: PT is
        // 1.4-1.8x faster), and the camera's lens code only under a thin lens. Kernels fetched per
        // frame pick the defines up at once; the graph is recompiled for passes that keep
        // pipelines.
        ShaderDefines scene;
        if (mScene->shapesMoveOverShutter()) scene.emplace("LOOM_SHAPE_MOTION_BLUR", "1");
        if (mSceneSpecialization) {
            scene.emplace("LOOM_SCENE_MATERIALS", fmt::format("{:#x}u", mScene->materialTypes()));
            scene.emplace("LOOM_SCENE_LIGHTS", fmt::format("{:#x}u", mScene->lightTypes()));
            scene.emplace("LOOM_SCENE_TEXTURES", fmt::format("{:#x}u", mScene->textureUses()));
            // The thin-lens code (lens sampling, primary-hit reconnection) only under a lens.
            scene.emplace("LOOM_SCENE_THIN_LENS", mScene->thinLens() ? "1" : "0");
        }
        if (scene != mSceneDefines) {
            ShaderDefines defines = mCompiler->globalDefines();
            for (const auto& [name, value] : mSceneDefines) defines.erase(name);
            for (const auto& [name, value] : scene) defines[name] = value;
            mCompiler->setGlobalDefines(std::move(defines));
            std::string why;
            for (const auto& [name, value] : scene) why += fmt::format(" {}={}", name, value);
            mGraph->invalidate("kernels specialised to the scene:" + (why.empty() ? " none" : why));
            mSceneDefines = std::move(scene);
        }
        in.scene = mScene.get();
        in.externalRevision += mScene->revision() << 32;
    }
    mGraph->execute(*mGpu, *mShaders, mWidth, mHeight, in);
    ++mFrames;
}

std::unique_ptr<RenderGraph> Renderer::setGraph(std::unique_ptr<RenderGraph> graph) {
    if (!graph) throw UserError("setGraph: no graph");
    mCompiler->addSearchPath(graph->sourceDir());
    std::swap(mGraph, graph);
    ++mExternalRevision;
    return graph;
}

void Renderer::resize(uint32_t width, uint32_t height) {
    mWidth = width;
    mHeight = height;
}

void Renderer::reset() {
    ++mExternalRevision;
    mGraph->resetHistory();
}

ImageData Renderer::readOutput(const std::string& port) {
    if (!mGraph->compiled()) frame();
    auto tex = mGraph->outputTexture(port);
    if (!tex) {
        std::string list;
        for (auto& o : mGraph->outputs()) list += (list.empty() ? "" : ", ") + o;
        throw UserError("no texture output '" + port + "' in graph '" + mGraph->name() +
                        "'; marked outputs: " + list);
    }
    return downloadImage(*mGpu, *tex);
}

void Renderer::checkNaN() {
    for (const auto& port : mGraph->outputs()) {
        auto tex = mGraph->outputTexture(port);
        if (!tex || !gpu::isFloatFormat(tex->format())) continue;
        ImageData img = downloadImage(*mGpu, *tex);
        for (size_t i = 0; i < img.pixels.size(); ++i)
            if (!std::isfinite(img.pixels[i])) {
                size_t p = i / img.channels;
                throw UserError(fmt::format("NaN/Inf in {} at pixel ({}, {}) channel {}", port,
                                            p % img.width, p / img.width, i % img.channels));
            }
    }
}

}  // namespace loom
