// GradientPathTracer (G-PT, Kettunen et al. 2015) against the reference path tracer, which
// shares none of its MIS weights, pixel pairing or gradient assembly: the mean of each frame's
// primal + emission equals the path tracer's image, and the mean of each gradient image plus the
// forward differences of the separately written emission equals the forward differences of the
// path tracer's image, on 8x8 regions (|z| < 4.5, Bonferroni for 64) and 2x2 regions (|z| < 3),
// with standard errors from the spread over frames (G-PT's frames are independent). Also under
// camera motion, and the biased variants must be detected by the same test.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "core/graph/Renderer.h"
#include "core/scene/SceneLoader.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/RegionStats.h"
#include "tests/support/ReuseComparison.h"

using namespace loom;
using namespace loom::test;

namespace {

constexpr int kBounces = 5;

// Luminance forward differences with the Neumann convention (0 in the last column / row).
ImageData differences(const ImageData& y, bool vertical) {
    ImageData d = y;
    for (uint32_t j = 0; j < y.height; ++j)
        for (uint32_t i = 0; i < y.width; ++i) {
            bool last = vertical ? j + 1 == y.height : i + 1 == y.width;
            float v =
                last ? 0.0f : y.at(vertical ? i : i + 1, vertical ? j + 1 : j, 0) - y.at(i, j, 0);
            for (uint32_t c = 0; c < 3; ++c)
                d.pixels[(size_t(j) * y.width + i) * y.channels + c] = v;
        }
    return d;
}

ImageData sum(const ImageData& a, const ImageData& b) {
    ImageData s = a;
    for (size_t i = 0; i < s.pixels.size(); ++i) s.pixels[i] += b.pixels[i];
    return s;
}

// Region statistics of the image and its two gradients, coarse and fine.
struct ImageAndGradients {
    RegionStats coarse[3] = {RegionStats(kCoarseRegions), RegionStats(kCoarseRegions),
                             RegionStats(kCoarseRegions)};
    RegionStats fine[3] = {RegionStats(8), RegionStats(8), RegionStats(8)};
    void add(const ImageData& image, const ImageData& dx, const ImageData& dy) {
        const ImageData* v[3] = {&image, &dx, &dy};
        for (int q = 0; q < 3; ++q) {
            coarse[q].add(*v[q]);
            fine[q].add(*v[q]);
        }
    }
};

struct GradientComparison {
    double z[3] = {0, 0, 0}, zFine[3] = {0, 0, 0};  // image, dx, dy
    bool unbiased() const {
        for (int q = 0; q < 3; ++q)
            if (z[q] >= kCoarseZ || zFine[q] >= kFineZ) return false;
        return true;
    }
    bool gradientsUnbiased() const {
        for (int q = 1; q < 3; ++q)
            if (z[q] >= kCoarseZ || zFine[q] >= kFineZ) return false;
        return true;
    }
};

std::unique_ptr<RenderGraph> gptGraph(const json& params) {
    json p = {{"maxBounces", kBounces}, {"samplesPerPixel", 1}};
    for (auto& [k, v] : params.items()) p[k] = v;
    json g = {{"name", "gpt_test"},
              {"passes", {{{"name", "gpt"}, {"type", "GradientPathTracer"}, {"params", p}}}},
              {"edges", json::array()},
              {"outputs", {"gpt.primal", "gpt.dx", "gpt.dy", "gpt.direct"}}};
    return RenderGraph::parse(g.dump(), "<test>");
}

// frames independent G-PT frames and path-traced frames at times f * dt.
GradientComparison compareGradients(const scene::Scene& scene, const json& params, int frames,
                                    float dt, int size = 32) {
    if (const char* e = std::getenv("LOOM_GPT_FRAMES")) frames = std::atoi(e);
    bool motionBlur = params.value("motionBlur", false);
    ImageAndGradients gpt, pt;
    {
        Renderer r(gpuContext(), gptGraph(params), size, size, 3);
        r.setScene(scene);
        for (int f = 0; f < frames; ++f) {
            r.setTime(f * dt);
            r.frame();
            ImageData direct = toLuminance(r.readOutput("gpt.direct"));
            ImageData primal = toLuminance(r.readOutput("gpt.primal"));
            gpt.add(sum(primal, direct),
                    sum(toLuminance(r.readOutput("gpt.dx")), differences(direct, false)),
                    sum(toLuminance(r.readOutput("gpt.dy")), differences(direct, true)));
        }
    }
    {
        Renderer r(gpuContext(), ptGraph(2, kBounces, motionBlur), size, size, 4);
        r.setScene(scene);
        for (int f = 0; f < frames; ++f) {
            r.setTime(f * dt);
            r.frame();
            ImageData y = toLuminance(r.readOutput("pt.color"));
            pt.add(y, differences(y, false), differences(y, true));
        }
    }
    GradientComparison c;
    for (int q = 0; q < 3; ++q) {
        c.z[q] = maxZ(gpt.coarse[q], pt.coarse[q]);
        c.zFine[q] = maxZ(gpt.fine[q], pt.fine[q]);
    }
    std::printf(
        "[ gpt      ] %s: max |z| image %.2f/%.2f, dx %.2f/%.2f, dy %.2f/%.2f (coarse/fine)\n",
        params.dump().c_str(), c.z[0], c.zFine[0], c.z[1], c.zFine[1], c.z[2], c.zFine[2]);
    return c;
}

}  // namespace

// Static camera: the Cornell box (diffuse: reconnection at the secondary hit) and the glossy
// scene (glossy primary hits: random replay up to a later reconnection vertex, or all the way).
TEST(GradientPathTracer, GradientsAndPrimalUnbiased) {
    for (const char* path : {"scenes/cornell_box.json", "scenes/glossy_spheres.json"}) {
        auto c = compareGradients(scene::loadScene(sourcePath(path)), json::object(), 160, 0.0f);
        EXPECT_TRUE(c.unbiased()) << path;
    }
}

// A moving camera: each frame's pose changes (translation and rotation of the scene's path).
TEST(GradientPathTracer, UnbiasedUnderCameraMotionAndMotionBlur) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    auto moving = compareGradients(box, json::object(), 160, 3.0f);
    EXPECT_TRUE(moving.unbiased()) << "moving camera";
    auto replay = compareGradients(box, {{"shift", "replay"}}, 96, 3.0f);
    EXPECT_TRUE(replay.unbiased()) << "random replay shift";
    auto blur = compareGradients(box, {{"motionBlur", true}}, 96, 3.0f);
    EXPECT_TRUE(blur.unbiased()) << "motion blur";
}

// The same comparison detects a flipped gradient sign and balance weights replaced by 1/2 (the
// pair's weights no longer sum to 1 where a shift fails).
TEST(GradientPathTracer, AblationsAreDetected) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    for (const char* ablation : {"flipGradientSign", "halfWeights"}) {
        auto c = compareGradients(box, {{"ablation", ablation}}, 160, 0.0f);
        EXPECT_FALSE(c.gradientsUnbiased()) << ablation << " was not detected";
    }
}

// The density G-PT's weights compare: for each candidate sub-path, the shift to its own pixel
// (gpt_pdf_check.comp) reproduces the generator's integrand and its reconnection density p_rc,
// for reconnection at the secondary hit (Cornell box), after replayed glossy vertices (glossy
// scene, roughness threshold 0.5) and at light vertices (NEE and emitter hits).
TEST(GradientPathTracer, ShiftDensityMatchesTheGenerator) {
    for (auto [path, threshold] : {std::pair{"scenes/cornell_box.json", 0.2},
                                   {"scenes/glossy_spheres.json", 0.2},
                                   {"scenes/glossy_spheres.json", 0.5}}) {
        json g = {
            {"name", "gpt_pdf_check"},
            {"passes",
             {{{"name", "check"},
               {"type", "ComputePass"},
               {"params",
                {{"shader", sourcePath("passes/gradient_domain/tests/gpt_pdf_check.comp")},
                 {"outputs", {{"check", {{"glsl", "checkImage"}, {"format", "rgba32f"}}}}},
                 {"persistent",
                  {{"counters", {{"glsl", "RestirCounters"}, {"kind", "buffer"}, {"bytes", 24}}}}},
                 {"constants",
                  {{"shift", {{"type", "uint"}, {"default", 0}}},
                   {"roughnessThreshold", {{"type", "float"}, {"default", threshold}}}}}}}}}},
            {"edges", json::array()},
            {"outputs", {"check.check"}}};
        Renderer r(gpuContext(), RenderGraph::parse(g.dump(), "<test>"), 48, 48, 5);
        r.loadScene(sourcePath(path));
        double candidates = 0, wrongF = 0, wrongPdf = 0, reconnected = 0;
        for (int f = 0; f < 4; ++f) {
            r.frame();
            ImageData img = r.readOutput("check.check");
            for (uint32_t i = 0; i < img.width * img.height; ++i) {
                candidates += img.pixels[i * 4];
                wrongF += img.pixels[i * 4 + 1];
                wrongPdf += img.pixels[i * 4 + 2];
                reconnected += img.pixels[i * 4 + 3];
            }
        }
        SCOPED_TRACE(std::string(path) + " roughness threshold " + std::to_string(threshold));
        std::printf(
            "[ gpt pdf  ] %s %.1f: %.0f candidates, %.0f reconnected, wrong F %.0f, wrong p_rc "
            "%.0f\n",
            path, threshold, candidates, reconnected, wrongF, wrongPdf);
        EXPECT_GT(candidates, 5000);
        EXPECT_GT(reconnected, 0.3 * candidates);
        // Float round-off at grazing reconnections only.
        EXPECT_LE(wrongF, 1e-3 * candidates);
        EXPECT_LE(wrongPdf, 1e-3 * candidates);
    }
}
