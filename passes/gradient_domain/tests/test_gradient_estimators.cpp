// The gradient estimators (GradientPathTracer: G-PT, Kettunen et al. 2015; GradientAfterReSTIR)
// against the reference path tracer, which shares none of their MIS weights, pixel pairing or
// gradient assembly: the mean primal + emission equals the path tracer's image, and the mean of
// each gradient image plus the forward differences of the separately written emission equals
// the forward differences of the path tracer's image, on 8x8 regions (|z| < 4.5, Bonferroni for
// 64) and 2x2 regions (|z| < 3), with standard errors from the spread over independent
// sequences. Static and moving cameras; the biased variants must be detected by the same test.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <tuple>
#include <vector>

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

// Luminance of an estimator's frame: image = primal + emission, its gradients plus the
// emission's forward differences.
void readFrame(Renderer& r, const std::string& node, ImageData out[3]) {
    ImageData direct = toLuminance(r.readOutput(node + ".direct"));
    out[0] = sum(toLuminance(r.readOutput(node + ".primal")), direct);
    out[1] = sum(toLuminance(r.readOutput(node + ".dx")), differences(direct, false));
    out[2] = sum(toLuminance(r.readOutput(node + ".dy")), differences(direct, true));
}

// `sequences` independent runs of `frames` frames (frame f at time f * dt, history reset and a
// new seed per run): each run's mean is one sample (ReSTIR's frames are correlated through
// reuse; G-PT's are not, and runs of one frame suffice). node empty: the path tracer.
ImageAndGradients sequenceStats(Renderer& r, const std::string& node, int sequences, int frames,
                                float dt) {
    ImageAndGradients stats;
    for (int s = 0; s < sequences; ++s) {
        r.setSeed(2000u + 7919u * uint32_t(s));
        r.reset();
        ImageData mean[3];
        for (int f = 0; f < frames; ++f) {
            r.setTime(f * dt);
            r.frame();
            ImageData v[3];
            if (node.empty()) {
                v[0] = toLuminance(r.readOutput("pt.color"));
                v[1] = differences(v[0], false);
                v[2] = differences(v[0], true);
            } else {
                readFrame(r, node, v);
            }
            for (int q = 0; q < 3; ++q) mean[q] = f == 0 ? v[q] : sum(mean[q], v[q]);
        }
        for (auto& m : mean)
            for (auto& x : m.pixels) x /= float(frames);
        stats.add(mean[0], mean[1], mean[2]);
    }
    return stats;
}

// The estimator `node` of `graph` against the path tracer (maxBounces `bounces`) over the same
// sequences and frame times.
GradientComparison compareGradients(const scene::Scene& scene, std::unique_ptr<RenderGraph> graph,
                                    const std::string& node, const std::string& label,
                                    int sequences, int frames, float dt, int bounces,
                                    bool motionBlur = false, int size = 32) {
    if (const char* e = std::getenv("LOOM_GRADIENT_SEQUENCES")) sequences = std::atoi(e);
    ImageAndGradients est, pt;
    {
        Renderer r(gpuContext(), std::move(graph), size, size, 3);
        r.setScene(scene);
        est = sequenceStats(r, node, sequences, frames, dt);
    }
    {
        Renderer r(gpuContext(), ptGraph(2, bounces, motionBlur), size, size, 4);
        r.setScene(scene);
        pt = sequenceStats(r, "", sequences, frames, dt);
    }
    GradientComparison c;
    for (int q = 0; q < 3; ++q) {
        c.z[q] = maxZ(est.coarse[q], pt.coarse[q]);
        c.zFine[q] = maxZ(est.fine[q], pt.fine[q]);
    }
    std::printf(
        "[ gradient ] %s: max |z| image %.2f/%.2f, dx %.2f/%.2f, dy %.2f/%.2f (coarse/fine)\n",
        label.c_str(), c.z[0], c.zFine[0], c.z[1], c.zFine[1], c.z[2], c.zFine[2]);
    return c;
}

// G-PT frames are independent: one-frame sequences, or 8 frames along a camera path.
GradientComparison compareGpt(const scene::Scene& scene, const json& params, int sequences,
                              float dt = 0.0f) {
    return compareGradients(scene, gptGraph(params), "gpt", "G-PT " + params.dump(),
                            dt == 0.0f ? sequences : sequences / 8, dt == 0.0f ? 1 : 8, dt,
                            kBounces, params.value("motionBlur", false));
}

// A gradient graph (Area ReSTIR based, 9 bounces; node "gradients") with parameters overridden.
GradientComparison compareGradientGraph(const std::string& file, const scene::Scene& scene,
                                        const json& overrides, int sequences, float dt,
                                        int frames = 8) {
    auto g = RenderGraph::load(sourcePath("graphs/" + file));
    for (auto& [key, value] : overrides.items()) g->setParam(key, value);
    return compareGradients(scene, std::move(g), "gradients", file + " " + overrides.dump(),
                            sequences, frames, dt, 9);
}

GradientComparison compareAfterReSTIR(const scene::Scene& scene, const json& overrides,
                                      int sequences, float dt) {
    return compareGradientGraph("gradient_after_restir.json", scene, overrides, sequences, dt);
}

GradientComparison compareGReSTIR(const scene::Scene& scene, const json& overrides, int sequences,
                                  float dt, int frames = 8) {
    return compareGradientGraph("grestir_pt.json", scene, overrides, sequences, dt, frames);
}

}  // namespace

// Static camera: the Cornell box (diffuse: reconnection at the secondary hit) and the glossy
// scene (glossy primary hits: random replay up to a later reconnection vertex, or all the way).
TEST(GradientPathTracer, GradientsAndPrimalUnbiased) {
    for (const char* path : {"scenes/cornell_box.json", "scenes/glossy_spheres.json"}) {
        auto c = compareGpt(scene::loadScene(sourcePath(path)), json::object(), 160);
        EXPECT_TRUE(c.unbiased()) << path;
    }
}

// A moving camera: each frame's pose changes (translation and rotation of the scene's path).
TEST(GradientPathTracer, UnbiasedUnderCameraMotionAndMotionBlur) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    auto moving = compareGpt(box, json::object(), 160, 3.0f);
    EXPECT_TRUE(moving.unbiased()) << "moving camera";
    auto replay = compareGpt(box, {{"shift", "replay"}}, 96, 3.0f);
    EXPECT_TRUE(replay.unbiased()) << "random replay shift";
    auto blur = compareGpt(box, {{"motionBlur", true}}, 96, 3.0f);
    EXPECT_TRUE(blur.unbiased()) << "motion blur";
}

// The same comparison detects a flipped gradient sign and balance weights replaced by 1/2 (the
// pair's weights no longer sum to 1 where a shift fails).
TEST(GradientPathTracer, AblationsAreDetected) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    for (const char* ablation : {"flipGradientSign", "halfWeights"}) {
        auto c = compareGpt(box, {{"ablation", ablation}}, 160);
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

// Gradient after ReSTIR: Area ReSTIR's final samples shifted to the neighbours, static and
// moving camera, and the flipped sign detected.
TEST(GradientAfterReSTIR, GradientsAndPrimalUnbiased) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    EXPECT_TRUE(compareAfterReSTIR(box, json::object(), 24, 0.0f).unbiased()) << "static camera";
    // 48 sequences: at 24 one 4x4-pixel block of dx read |z| 4.67, at 96 the worst is 2.34.
    EXPECT_TRUE(compareAfterReSTIR(box, json::object(), 48, 3.0f).unbiased()) << "moving camera";
    scene::Scene glossy = scene::loadScene(sourcePath("scenes/glossy_spheres.json"));
    EXPECT_TRUE(compareAfterReSTIR(glossy, json::object(), 24, 2.0f).unbiased())
        << "glossy, moving";
    EXPECT_FALSE(compareAfterReSTIR(box, {{"gradients.ablation", "flipGradientSign"}}, 24, 0.0f)
                     .gradientsUnbiased())
        << "flipped sign not detected";
}

// ReSTIR G-PT (graphs/grestir_pt.json): paired-pixel reservoirs with temporal and spatial reuse,
// with and without positivization, both spatial MIS weights, static and moving camera.
TEST(ReSTIRGPT, GradientsAndPrimalUnbiased) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    EXPECT_TRUE(compareGReSTIR(box, json::object(), 24, 0.0f).unbiased()) << "static camera";
    EXPECT_TRUE(compareGReSTIR(box, {{"pairs.positivization", false}}, 24, 0.0f).unbiased())
        << "without positivization";
    EXPECT_TRUE(compareGReSTIR(box, {{"pairSpatial.mis", "balance"}}, 24, 0.0f).unbiased())
        << "balance heuristic in spatial reuse";
    EXPECT_TRUE(compareGReSTIR(box, json::object(), 48, 3.0f).unbiased()) << "moving camera";
    // Glossy pairs (random replay through rough gold, tiny bright lights). The static camera's
    // sky is noiseless on both sides: its float rounding once read as |z| 8847 (RegionStats).
    scene::Scene glossy = scene::loadScene(sourcePath("scenes/glossy_spheres.json"));
    EXPECT_TRUE(compareGReSTIR(glossy, json::object(), 24, 0.0f).unbiased()) << "glossy, static";
    EXPECT_TRUE(compareGReSTIR(glossy, json::object(), 24, 2.0f).unbiased()) << "glossy, moving";
}

namespace {

// The gradient images of 4 frames of graphs/grestir_pt.json (moving camera), seed 7.
std::vector<ImageData> grestirFrames(const scene::Scene& scene, const json& overrides) {
    auto g = RenderGraph::load(sourcePath("graphs/grestir_pt.json"));
    for (auto& [key, value] : overrides.items()) g->setParam(key, value);
    Renderer r(gpuContext(), std::move(g), 32, 32, 7);
    r.setScene(scene);
    std::vector<ImageData> images;
    for (int f = 0; f < 4; ++f) {
        r.setTime(f * 2.0f);
        r.frame();
        images.push_back(r.readOutput("gradients.dx"));
        images.push_back(r.readOutput("gradients.dy"));
    }
    return images;
}

// Largest and mean absolute difference of two image sequences, over the first's largest and
// mean absolute value.
std::pair<double, double> relativeDifference(const std::vector<ImageData>& a,
                                             const std::vector<ImageData>& b) {
    double maxDiff = 0, maxA = 0, sumDiff = 0, sumA = 0;
    for (size_t k = 0; k < a.size(); ++k)
        for (size_t i = 0; i < a[k].pixels.size(); ++i) {
            double d = std::abs(double(a[k].pixels[i]) - b[k].pixels[i]),
                   v = std::abs(a[k].pixels[i]);
            maxDiff = std::max(maxDiff, d);
            maxA = std::max(maxA, v);
            sumDiff += d;
            sumA += v;
        }
    return {maxA > 0 ? maxDiff / maxA : 1.0, sumA > 0 ? sumDiff / sumA : 1.0};
}

}  // namespace

// The outer shift's Jacobian. In the mixed measure the hybrid shift's is 1; in the solid-angle
// measure (the paper's) every outer shift carries the reconnection Jacobian solid_src /
// solid_dst, and with it the estimator is the same function of the random numbers: the images
// agree to float round-off, while without it they differ everywhere. (Against the path tracer
// the lost Jacobian is hard to see: with the balance heuristic a point's weights sum to
// (a + c) / (a rho + c), rho the Jacobian, which averages to about 1 over a symmetric
// neighbourhood; 512 sequences of spatial-only reuse did not resolve it.) Under a thin lens the
// outer shift by primary-hit reconnection (lens-space Jacobian) is unbiased.
TEST(ReSTIRGPT, OuterShiftJacobian) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    auto mixed = grestirFrames(box, {{"pairs.measure", "mixed"}});
    auto solid = grestirFrames(box, {{"pairs.measure", "solidAngle"}});
    auto dropped = grestirFrames(
        box, {{"pairs.measure", "solidAngle"}, {"pairSpatial.ablation", "dropOuterJacobian"}});
    auto [maxSame, meanSame] = relativeDifference(mixed, solid);
    auto [maxDropped, meanDropped] = relativeDifference(mixed, dropped);
    std::printf(
        "[ gradient ] mixed vs solid-angle measure: max %.3g, mean %.3g relative difference; "
        "without the outer Jacobian: max %.3g, mean %.3g\n",
        maxSame, meanSame, maxDropped, meanDropped);
    EXPECT_LE(maxSame, 1e-4);
    EXPECT_GT(meanDropped, 0.02) << "the lost Jacobian changed nothing";

    scene::Scene lens =
        withThinLens(scene::loadScene(sourcePath("scenes/cornell_box.json")), 1.0f, 3.0f);
    EXPECT_TRUE(
        compareGReSTIR(lens,
                       {{"pairSpatial.outerShift", "primaryReconnect"}, {"pairSpatial.radius", 10}},
                       24, 0.0f)
            .unbiased())
        << "primary-hit reconnection as the outer shift";
}

// Under positivization the neighbour's reservoir of the other sign reused, and the gradients'
// sign flipped, must be detected.
TEST(ReSTIRGPT, AblationsAreDetected) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    EXPECT_FALSE(compareGReSTIR(box, {{"pairSpatial.ablation", "reuseAcrossSigns"}}, 24, 0.0f)
                     .gradientsUnbiased())
        << "reuse across signs not detected";
    EXPECT_FALSE(compareGReSTIR(box, {{"gradients.ablation", "flipGradientSign"}}, 24, 0.0f)
                     .gradientsUnbiased())
        << "flipped sign not detected";
}

namespace {

// Region statistics of graph's addDirect.output (the reconstruction plus the emission seen at
// the primary hit) after `frames` frames, one sample per sequence, and of the path tracer's mean
// over the same frames.
struct ReconstructionComparison {
    RegionStats est[2] = {RegionStats(kCoarseRegions), RegionStats(8)};
    RegionStats pt[2] = {RegionStats(kCoarseRegions), RegionStats(8)};
    double z[2] = {0, 0};
};

ReconstructionComparison compareReconstruction(const scene::Scene& scene, const std::string& file,
                                               const json& overrides, int sequences, int frames) {
    if (const char* e = std::getenv("LOOM_GRADIENT_SEQUENCES")) sequences = std::atoi(e);
    ReconstructionComparison c;
    {
        auto g = RenderGraph::load(sourcePath("graphs/" + file));
        for (auto& [key, value] : overrides.items()) g->setParam(key, value);
        Renderer r(gpuContext(), std::move(g), 32, 32, 3);
        r.setScene(scene);
        for (int s = 0; s < sequences; ++s) {
            r.setSeed(2000u + 7919u * uint32_t(s));
            r.reset();
            for (int f = 0; f < frames; ++f) r.frame();
            ImageData img = toLuminance(r.readOutput("addDirect.output"));
            for (auto& st : c.est) st.add(img);
        }
    }
    {
        Renderer r(gpuContext(), ptGraph(2, 9, false), 32, 32, 4);
        r.setScene(scene);
        ImageAndGradients pt = sequenceStats(r, "", sequences, frames, 0.0f);
        c.pt[0] = pt.coarse[0];
        c.pt[1] = pt.fine[0];
    }
    for (int q = 0; q < 2; ++q) c.z[q] = maxZ(c.est[q], c.pt[q]);
    return c;
}

}  // namespace

// The screened Poisson L2 solve is linear in its inputs, so the mean of L2 reconstructions of
// unbiased primal and gradient estimates is the image: the reconstructed frames of ReSTIR G-PT
// and G-PT match the path tracer on regions. L1 (IRLS) is not linear: its bias per region is
// reported (the Cornell box's 2x2 regions, relative to the path tracer, with z) and must be
// resolved by the same comparison.
TEST(ReSTIRGPT, L2ReconstructionUnbiasedL1Reported) {
    scene::Scene box = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    // G-PT's frames are independent: sequences of one frame.
    for (auto [file, sequences, frames] :
         {std::tuple{"grestir_pt.json", 24, 8}, {"gpt.json", 96, 1}}) {
        auto c = compareReconstruction(box, file, json::object(), sequences, frames);
        std::printf("[ poisson  ] %s L2: max |z| %.2f/%.2f (coarse/fine)\n", file, c.z[0], c.z[1]);
        EXPECT_LT(c.z[0], kCoarseZ) << file;
        EXPECT_LT(c.z[1], kFineZ) << file;
    }
    auto c = compareReconstruction(box, "grestir_pt.json", {{"poisson.solver", "l1"}}, 16, 8);
    std::printf(
        "[ poisson  ] grestir_pt.json L1: max |z| %.2f/%.2f (coarse/fine); bias per 2x2 "
        "region (luminance, relative):",
        c.z[0], c.z[1]);
    for (int i = 0; i < kCoarseRegions * kCoarseRegions; ++i) {
        double e = c.est[0].mean(i * 3), p = c.pt[0].mean(i * 3);
        double se = std::sqrt(c.est[0].stderr2(i * 3) + c.pt[0].stderr2(i * 3));
        std::printf(" %+.2f%% (z %.1f)", 100.0 * (e - p) / p, (e - p) / se);
    }
    std::printf("\n");
    // The same comparison resolves it (the darkening of L1 reconstruction, 2-5 %).
    EXPECT_TRUE(c.z[0] >= kCoarseZ || c.z[1] >= kFineZ) << "L1's bias was not resolved";
}
