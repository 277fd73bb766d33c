// Specular manifold sampling (passes/sms, shaders/lib/manifold): the walk against closed-form
// solutions (mirror image source, Snell's law on a flat interface, a sphere's reflection), the
// generalized geometric term against finite differences of re-solved chains, the Bernoulli
// estimator's E[K] = 1/p, unbiasedness against the reference path tracer, double counting,
// and bad input. Tolerances come from measured standard errors or from float precision stated
// where used.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <glm/glm.hpp>
#include <random>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "core/scene/SceneLoader.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/TestSupport.h"

namespace loom {
namespace {

std::string sourcePath(const std::string& rel) { return std::string(LOOM_SOURCE_DIR) + "/" + rel; }

scene::Scene sceneFromJson(const std::string& text, const test::TempDir& dir,
                           const std::string& name = "scene.json") {
    std::ofstream(dir / name) << text;
    return scene::loadScene(dir / name);
}

// A mirror (perfect conductor, facing down) at y = 2 over a diffuse floor, point light below it.
const char* kMirrorScene = R"({
  "loom_scene": 1,
  "camera": {"origin": [0, 1.5, 3], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
  "materials": {"mirror": {"type": "conductor", "metal": "none"},
                "floor": {"type": "diffuse", "reflectance": 0.5}},
  "shapes": [
    {"name": "floor", "type": "rectangle", "material": "floor", "caustic_receiver": true,
     "transform": [{"scale": 4}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}]},
    {"name": "mirror", "type": "rectangle", "material": "mirror", "caustic_caster": true,
     "transform": [{"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 2, 0]}]}],
  "lights": [{"type": "point", "position": [0.3, 1, 0], "intensity": 1, "caustic_emitter": true}]
})";

struct WalkInput {
    glm::vec3 x0, ng0, y, ny, seed;
    bool straight = false;
    int constraint = 0;  // 0 angle difference, 1 half vector
    int maxIterations = 20;
    float threshold = 1e-5f;
    int maxChain = 2;
    glm::vec3 es{1, 0, 0}, et{0, 0, 1};
};
struct WalkResult {
    int phase, iterations, k;
    float det, beta, error;
    glm::vec3 v[4];
};
constexpr int kConverged = 3;

std::vector<WalkResult> runWalks(const scene::Scene& scene, const std::vector<WalkInput>& in) {
    test::TempDir dir("loom-sms-walk");
    uint32_t n = uint32_t(in.size());
    ImageData img;
    img.width = n;
    img.height = 8;
    img.channels = 4;
    img.pixels.assign(size_t(n) * 8 * 4, 0.0f);
    auto put = [&](uint32_t x, uint32_t row, glm::vec4 v) {
        float* p = &img.pixels[(size_t(row) * n + x) * 4];
        p[0] = v.x, p[1] = v.y, p[2] = v.z, p[3] = v.w;
    };
    for (uint32_t i = 0; i < n; ++i) {
        const auto& w = in[i];
        put(i, 0, glm::vec4(w.x0, 0));
        put(i, 1, glm::vec4(w.ng0, 0));
        put(i, 2, glm::vec4(w.y, 0));
        put(i, 3, glm::vec4(w.ny, 0));
        put(i, 4, glm::vec4(w.seed, w.straight ? 1 : 0));
        put(i, 5, glm::vec4(w.constraint, w.maxIterations, w.threshold, w.maxChain));
        put(i, 6, glm::vec4(w.es, 0));
        put(i, 7, glm::vec4(w.et, 0));
    }
    writeImage(dir / "in.exr", img);
    json g = {{"passes",
               {{{"name", "in"}, {"type", "ImageLoader"}, {"params", {{"path", "in.exr"}}}},
                {{"name", "k"},
                 {"type", "ComputePass"},
                 {"params",
                  {{"shader", sourcePath("passes/sms/tests/manifold_walk.comp")},
                   {"inputs", {{"input", {{"glsl", "inputImage"}, {"format", "rgba32f"}}}}},
                   {"outputs", {{"output", {{"glsl", "outputImage"}}}}}}}}}},
              {"edges", json::array({json::array({"in.output", "k.input"})})},
              {"outputs", {"k.output"}}};
    Renderer r(test::gpuContext(), RenderGraph::parse(g.dump(), dir / "graph.json"), n, 8);
    r.setScene(scene);
    r.frame();
    ImageData out = r.readOutput("k.output");
    std::vector<WalkResult> res(n);
    auto get = [&](uint32_t x, uint32_t row) {
        const float* p = &out.pixels[(size_t(row) * n + x) * out.channels];
        return glm::vec4(p[0], p[1], p[2], p[3]);
    };
    for (uint32_t i = 0; i < n; ++i) {
        glm::vec4 a = get(i, 0), b = get(i, 5);
        res[i] = {int(a.x), int(a.y), int(a.z), a.w, b.x, b.y, {}};
        for (int j = 0; j < 4; ++j) res[i].v[j] = glm::vec3(get(i, 1 + j));
    }
    return res;
}

TEST(SpecularManifoldWalk, FlatMirrorConvergesToTheImageSourcePoint) {
    test::TempDir dir("loom-sms");
    auto scene = sceneFromJson(kMirrorScene, dir);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<WalkInput> in;
    glm::vec3 light(0.3f, 1.0f, 0.0f);
    for (int i = 0; i < 64; ++i) {
        WalkInput w;
        w.x0 = glm::vec3(u(rng) * 0.8f, 0, u(rng) * 0.8f);
        w.ng0 = glm::vec3(0, 1, 0);
        w.y = light;
        w.ny = glm::vec3(0);
        w.seed = glm::vec3(u(rng) * 0.9f, 2, u(rng) * 0.9f);
        w.constraint = i % 2;
        in.push_back(w);
    }
    auto res = runWalks(scene, in);
    int converged = 0;
    for (size_t i = 0; i < in.size(); ++i) {
        // Image source y' = (0.3, 3, 0): the reflection point is where x0 -> y' crosses y = 2.
        glm::vec3 img(light.x, 3.0f, light.z);
        float t = (2.0f - in[i].x0.y) / (img.y - in[i].x0.y);
        glm::vec3 expect = in[i].x0 + t * (img - in[i].x0);
        if (std::abs(expect.x) > 1 || std::abs(expect.z) > 1) continue;
        EXPECT_EQ(res[i].phase, kConverged)
            << "walk " << i << " iterations " << res[i].iterations << " k " << res[i].k << " beta "
            << res[i].beta << " error " << res[i].error << " v0 " << res[i].v[0].x << ","
            << res[i].v[0].y << "," << res[i].v[0].z << " expected " << expect.x << "," << expect.z;
        if (res[i].phase != kConverged) continue;
        ++converged;
        EXPECT_EQ(res[i].k, 1);
        EXPECT_LT(glm::length(res[i].v[0] - expect), 1e-4f) << "walk " << i;
        EXPECT_LT(res[i].error, 1e-5f);
    }
    EXPECT_GT(converged, 40);
}

}  // namespace
}  // namespace loom
