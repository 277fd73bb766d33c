// Every project scene and every shared Mitsuba scene loads, uploads and renders with the
// reference path tracer without NaN/Inf, and is not black.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/graph/Renderer.h"
#include "core/scene/SceneLoader.h"

using namespace loom;
namespace fs = std::filesystem;

namespace {

std::shared_ptr<gpu::Context> sharedGpu() {
    static std::shared_ptr<gpu::Context> gpu = [] {
        gpu::Context::Options o;
        o.cacheDir = (fs::temp_directory_path() / "loom-test-cache").string();
        return gpu::Context::create(o);
    }();
    return gpu;
}

void renderWithoutNaN(const std::string& path) {
    auto graph = RenderGraph::parse(R"({"name": "t", "passes": [
        {"name": "pt", "type": "PathTracer", "params": {"maxBounces": 4}}],
        "outputs": ["pt.color"]})",
                                    "<test>");
    Renderer r(sharedGpu(), std::move(graph), 32, 24, 1);
    scene::SceneLoadOptions options;
    options.defines["alpha"] = "0.1";  // sms-plane/plane_rough_*.xml take it from the command line
    r.setScene(scene::loadScene(path, options));
    r.frames(2);
    ImageData img = r.readOutput("pt.color");
    double sum = 0.0;
    for (size_t i = 0; i < img.pixels.size(); ++i) {
        ASSERT_TRUE(std::isfinite(img.pixels[i]))
            << path << ": NaN/Inf at pixel " << i / 4 % img.width << "," << i / 4 / img.width;
        if (i % 4 != 3) sum += img.pixels[i];
    }
    EXPECT_GT(sum, 0.0) << path << " renders black";
}

std::vector<std::string> filesIn(const fs::path& dir, const std::string& ext, bool recursive) {
    std::vector<std::string> out;
    if (!fs::exists(dir)) return out;
    auto add = [&](const fs::directory_entry& e) {
        if (e.is_regular_file() && e.path().extension() == ext) out.push_back(e.path().string());
    };
    if (recursive)
        for (auto& e : fs::recursive_directory_iterator(dir)) add(e);
    else
        for (auto& e : fs::directory_iterator(dir)) add(e);
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace

TEST(SceneRender, ProjectScenes) {
    auto files = filesIn(fs::path(LOOM_SOURCE_DIR) / "scenes", ".json", false);
    ASSERT_FALSE(files.empty());
    for (auto& f : files) {
        SCOPED_TRACE(f);
        renderWithoutNaN(f);
    }
}

TEST(SceneRender, SharedMitsubaScenes) {
    fs::path shared = fs::path(LOOM_SOURCE_DIR) / ".." / "shared" / "scenes";
    auto files = filesIn(shared, ".xml", true);
    if (files.empty()) GTEST_SKIP() << "no ../shared/scenes in this checkout";
    // Meshes PROVENANCE.md lists as not obtainable; the loader test checks their error.
    std::erase_if(files, [](const std::string& f) {
        return f.find("sms-slab/") != std::string::npos ||
               f.find("scene_original_obj") != std::string::npos;
    });
    for (auto& f : files) {
        SCOPED_TRACE(f);
        renderWithoutNaN(f);
    }
}
