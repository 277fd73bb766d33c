// ReSTIR PT: unbiasedness against the reference path tracer, and its parts (shift bookkeeping,
// Jacobians against finite differences, MIS weights summing to 1, the failed-shift bias class).
// The statistics (sequences as the independent unit, 2x2 and 8x8 regions) are
// tests/support/ReuseComparison.h's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>

#include "core/graph/Renderer.h"
#include "core/scene/SceneGpu.h"
#include "core/scene/SceneLoader.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/RegionStats.h"
#include "tests/support/ReuseComparison.h"
#include "tests/support/TestSupport.h"

using namespace loom;
using loom::test::maxZ;
using loom::test::RegionStats;

using namespace loom::test;

// Unbiasedness: the mean of ReSTIR PT over independent sequences equals the reference within 3
// standard errors in every 2x2 region (4 comparisons; P(|z| > 3) under the null ~0.01) and
// within 4.5 in every 8x8 region (64 comparisons, ~0.01 together).
TEST(ReSTIRPT, UnbiasedCornellStaticCamera) {
    auto c =
        compareWithReference(sourcePath("scenes/cornell_box.json"), "restir_pt.json", {}, 0.0f);
    EXPECT_TRUE(c.unbiased()) << "restir " << c.restir << " vs reference " << c.reference;
}

TEST(ReSTIRPT, UnbiasedCornellMovingCamera) {
    // cornell_box.json's camera path: 3 frames of the path per rendered frame.
    auto c =
        compareWithReference(sourcePath("scenes/cornell_box.json"), "restir_pt.json", {}, 3.0f);
    EXPECT_TRUE(c.unbiased()) << "restir " << c.restir << " vs reference " << c.reference;
}

// Russian roulette from the first vertex after the reconnection vertex (the default starts at
// vertex 5, which short test paths rarely reach): survival decisions belong to the pixel's
// source density, never to the integrand that shifts carry.
TEST(ReSTIRPT, UnbiasedWithRussianRouletteInTheSuffix) {
    auto c = compareWithReference(sourcePath("scenes/cornell_box.json"), "restir_pt.json",
                                  {{"initial.rrDepth", 1}}, 0.0f);
    EXPECT_TRUE(c.unbiased()) << "restir " << c.restir << " vs reference " << c.reference;
}

TEST(ReSTIRPT, UnbiasedGlossyMovingCamera) {
    auto c =
        compareWithReference(sourcePath("scenes/glossy_spheres.json"), "restir_pt.json", {}, 2.0f);
    EXPECT_TRUE(c.unbiased()) << "restir " << c.restir << " vs reference " << c.reference;
}

TEST(ReSTIRPT, UnbiasedEveryShiftAndAblation) {
    std::string scene = sourcePath("scenes/glossy_spheres.json");
    for (const char* shift : {"reconnection", "replay"}) {
        auto c = compareWithReference(scene, "restir_pt.json", {{"initial.shift", shift}}, 2.0f);
        EXPECT_TRUE(c.unbiased()) << shift << ": restir " << c.restir << " vs " << c.reference;
    }
    // Hybrid with a high roughness threshold: the spheres with alpha <= 0.2 are then replayed
    // through before reconnecting (k >= 3), which the default threshold (alpha > 0.04) rarely
    // needs on this scene.
    {
        auto c = compareWithReference(scene, "restir_pt.json",
                                      {{"initial.roughnessThreshold", 0.5}}, 2.0f);
        EXPECT_TRUE(c.unbiased()) << "threshold 0.5: restir " << c.restir << " vs " << c.reference;
    }
    for (const char* mis : {"pairwise", "balance"}) {
        auto c = compareWithReference(scene, "restir_pt.json", {{"spatial.mis", mis}}, 2.0f);
        EXPECT_TRUE(c.unbiased()) << "spatial " << mis << ": restir " << c.restir << " vs "
                                  << c.reference;
    }
    for (const char* graph : {"restir_pt_spatial_only.json", "restir_pt_temporal_only.json"}) {
        auto c = compareWithReference(scene, graph, {}, 2.0f);
        EXPECT_TRUE(c.unbiased()) << graph << ": restir " << c.restir << " vs " << c.reference;
    }
}

// Moving shapes: the Cornell box with the tall box sliding and turning over the 8 frames of a
// sequence (static camera). Temporal shifts evaluate each domain in its own frame's geometry
// (the previous frame's vertices and BVH stay on the GPU), and paths whose cached suffix could
// have changed do not cross frames (temporal.movingSuffix = reject). Reusing that suffix
// unchecked is biased near the box (+27% in a 4x4-pixel block next to its base, -9% beside it),
// which the fine regions see; re-evaluating previous targets in this frame's geometry instead
// (the previous version) was 2% dark overall.
TEST(ReSTIRPT, UnbiasedWithMovingShapes) {
    json scene = json::parse(test::readFile(sourcePath("scenes/cornell_box.json")));
    scene["camera"].erase("path");
    for (auto& shape : scene["shapes"])
        if (shape["name"] == "tall_box")
            shape["path"] = json::parse(R"([{"time": 0, "translate": [0, 0, 0]},
                {"time": 7, "translate": [0.35, 0, 0.05], "rotate": {"axis": [0, 1, 0], "angle": 50}}])");
    test::TempDir tmp("loom-restir-moving");
    std::string path = tmp / "cornell_moving.json";
    test::writeFile(path, scene.dump());
    scene::Scene moving = scene::loadScene(path);
    auto c = compareWithReference(moving, "restir_pt.json", {}, 1.0f);
    EXPECT_TRUE(c.unbiased()) << "restir " << c.restir << " vs reference " << c.reference;
    auto cached =
        compareWithReference(moving, "restir_pt.json", {{"temporal.movingSuffix", "reuse"}}, 1.0f);
    EXPECT_FALSE(cached.unbiased()) << "the stale-suffix bias was not detected";
    // Area ReSTIR re-traces primary rays: in the previous frame's geometry for its partner.
    auto area = compareWithReference(moving, "area_restir.json", {}, 1.0f);
    EXPECT_TRUE(area.unbiased()) << "area: restir " << area.restir << " vs " << area.reference;
}

// Area ReSTIR: film and lens samples are part of the path sample and are replayed at the
// destination pixel; unbiased with a static and a moving camera, with and without depth of field.
TEST(AreaReSTIR, UnbiasedStaticAndMovingCamera) {
    std::string scene = sourcePath("scenes/cornell_box.json");
    // 48 sequences: at 24 the static case read |z| 3.28 in one coarse region (-1.0%) after the
    // NEE shadow-ray fix changed every random path; at 48 it is 2.15 (-0.56%), at 96 2.27, so
    // chance, and the coarse threshold of 3 stays.
    for (float dt : {0.0f, 3.0f}) {
        auto c = compareWithReference(scene::loadScene(scene), "area_restir.json", {}, dt, 32,
                                      std::max(48, defaultSequences()));
        EXPECT_TRUE(c.unbiased()) << "dt " << dt << ": " << c.restir << " vs " << c.reference;
    }
}

// Fractional motion vectors: both temporal variants and the integer/copy reprojection.
TEST(AreaReSTIR, UnbiasedTemporalVariants) {
    std::string scene = sourcePath("scenes/glossy_spheres.json");
    for (const char* variant : {"fast", "robust", "copy"}) {
        auto c = compareWithReference(scene, "area_restir.json",
                                      {{"temporal.areaReprojection", variant}}, 2.0f);
        EXPECT_TRUE(c.unbiased()) << variant << ": " << c.restir << " vs " << c.reference;
    }
    // Several candidates per pixel, each with its own film and lens sample and primary ray.
    auto c = compareWithReference(scene, "area_restir.json", {{"initial.candidates", 3}}, 2.0f);
    EXPECT_TRUE(c.unbiased()) << "3 candidates: " << c.restir << " vs " << c.reference;
}

TEST(AreaReSTIR, UnbiasedWithDepthOfField) {
    // Focused near the front of the boxes: the back wall's circle of confusion spans a few
    // pixels, where primary-hit reconnection succeeds for near neighbours.
    scene::Scene s =
        withThinLens(scene::loadScene(sourcePath("scenes/cornell_box.json")), 0.4f, 5.5f);
    for (const char* graph : {"area_restir.json", "restir_pt.json"}) {
        auto c = compareWithReference(s, graph, {}, 3.0f);
        EXPECT_TRUE(c.unbiased()) << graph << ": " << c.restir << " vs " << c.reference;
    }
    for (const char* shift : {"copy", "reconnect"}) {
        auto c = compareWithReference(s, "area_restir.json", {{"spatial.dofShift", shift}}, 3.0f);
        EXPECT_TRUE(c.unbiased()) << shift << ": " << c.restir << " vs " << c.reference;
    }
    // Temporal reuse by primary-hit reconnection alone (the default combines it with copy).
    {
        auto c =
            compareWithReference(s, "area_restir.json", {{"temporal.dofShift", "reconnect"}}, 3.0f);
        EXPECT_TRUE(c.unbiased()) << "temporal reconnect: " << c.restir << " vs " << c.reference;
    }
}

// The primary-hit reconnection Jacobian (lens sample space) against central finite differences
// on a defocused Cornell box, and the inverse concentric disk mapping's round trip.
TEST(AreaReSTIR, PrimaryHitReconnectionJacobian) {
    // Focused at 3: everything strongly defocused.
    scene::Scene s =
        withThinLens(scene::loadScene(sourcePath("scenes/cornell_box.json")), 0.4f, 3.0f);
    json g = {
        {"name", "lens_jacobian"},
        {"passes",
         {{{"name", "k"},
           {"type", "ComputePass"},
           {"params",
            {{"shader",
              std::string(LOOM_SOURCE_DIR) + "/passes/restir_pt/tests/restir_lens_jacobian.comp"},
             {"outputs", {{"result", {{"glsl", "resultImage"}, {"format", "rgba32f"}}}}},
             {"persistent",
              {{"counters", {{"glsl", "RestirCounters"}, {"kind", "buffer"}, {"bytes", 20}}}}}}}}}},
        {"edges", json::array()},
        {"outputs", {"k.result"}}};
    Renderer r(test::gpuContext(), RenderGraph::parse(g.dump(), "<test>"), 48, 48, 1);
    r.setScene(s);
    r.frame();
    ImageData img = r.readOutput("k.result");
    int checked = 0, bad = 0, roundTrips = 0, badTrips = 0;
    for (uint32_t i = 0; i < img.width * img.height; ++i) {
        const float* p = &img.pixels[i * 4];
        EXPECT_LT(p[2], 1e-5f) << "inverse concentric mapping, pixel " << i;
        if (p[3] >= 0) {  // shifted there: the shift back restores the lens sample, J_back = 1/J
            ++roundTrips;
            if (p[3] > 1e-3f && ++badTrips <= 5)
                ADD_FAILURE() << "pixel " << i << ": round trip error " << p[3]
                              << (p[3] > 1e8f ? " (the shift back failed)" : "");
        }
        if (p[1] < 0) continue;
        ++checked;
        if (std::abs(p[0] - p[1]) > 1e-2 * p[1] && ++bad <= 5)
            ADD_FAILURE() << "pixel " << i << ": J " << p[0] << " finite differences " << p[1];
    }
    EXPECT_GT(checked, 1000);
    EXPECT_EQ(bad, 0);
    EXPECT_GT(roundTrips, 1000);
    EXPECT_EQ(badTrips, 0);
}

// The known bias class: a history whose shift fails must not stay in the MIS denominator. The
// correct confidence weights (1/|Z|) are unbiased; counting failed shifts darkens the image and
// this comparison must see it (so the unbiasedness tests above can fail).
TEST(ReSTIRPT, FailedShiftInDenominatorIsDetected) {
    std::string scene = sourcePath("scenes/glossy_spheres.json");
    auto good = compareWithReference(scene, "restir_pt_temporal_only.json",
                                     {{"temporal.mis", "uniform"}}, 2.0f);
    EXPECT_TRUE(good.unbiased()) << "uniform MIS: " << good.restir << " vs " << good.reference;
    auto bad = compareWithReference(
        scene, "restir_pt_temporal_only.json",
        {{"temporal.mis", "uniform"}, {"temporal.countFailedShifts", true}}, 2.0f);
    EXPECT_GT(bad.z, 3.0) << "the failed-shift bias was not detected: " << bad.restir << " vs "
                          << bad.reference;
    EXPECT_LT(bad.restir, bad.reference) << "counting failed shifts must darken";
}

namespace {

// GBuffer -> ReSTIRPTInitial -> tests/restir_shift_check.comp.
std::unique_ptr<RenderGraph> shiftCheckGraph(const std::string& shift,
                                             const std::string& reuse = "path",
                                             double roughnessThreshold = 0.2) {
    json g = {
        {"name", "restir_shift_check"},
        {"passes",
         {{{"name", "gbuffer"}, {"type", "GBuffer"}},
          {{"name", "initial"},
           {"type", "ReSTIRPTInitial"},
           {"params",
            {{"shift", shift}, {"reuse", reuse}, {"roughnessThreshold", roughnessThreshold}}}},
          {{"name", "check"},
           {"type", "ComputePass"},
           {"params",
            {{"shader",
              std::string(LOOM_SOURCE_DIR) + "/passes/restir_pt/tests/restir_shift_check.comp"},
             {"inputs",
              {{"reservoirs", {{"glsl", "ReservoirsIn"}, {"kind", "buffer"}}},
               {"primary", {{"glsl", "PrimaryIn"}, {"kind", "buffer"}}}}},
             {"outputs", {{"check", {{"glsl", "checkImage"}, {"format", "rgba32f"}}}}},
             {"persistent",
              {{"counters", {{"glsl", "RestirCounters"}, {"kind", "buffer"}, {"bytes", 20}}}}}}}}}},
        {"edges", json::array({json::array({"gbuffer.vbuffer", "initial.vbuffer"}),
                               json::array({"gbuffer.sample", "initial.sample"}),
                               json::array({"initial.reservoirs", "check.reservoirs"}),
                               json::array({"initial.primary", "check.primary"})})},
        {"outputs", {"check.check"}}};
    return RenderGraph::parse(g.dump(), "<test>");
}

}  // namespace

// Shifting a path to its own primary hit must reproduce the stored integrand (the mixed-measure
// bookkeeping of generation and shift agree, and T^-1(T(x)) = x: the stored sample is
// domain-free, so shifting there and back is this identity), for every shift and every path
// kind (reconnection at a surface, at a light, replay only); shifts to a neighbour mostly succeed.
TEST(ReSTIRPT, ShiftToOwnPixelReproducesIntegrand) {
    for (const char* scene : {"scenes/cornell_box.json", "scenes/glossy_spheres.json"}) {
        // hybrid-0.5: roughness threshold 0.5, so that the glossy spheres are replayed through
        // before the reconnection vertex (k >= 3).
        for (std::string shift : {"hybrid", "hybrid-0.5", "reconnection", "replay", "area"}) {
            bool area = shift == "area";
            double threshold = shift == "hybrid-0.5" ? 0.5 : 0.2;
            if (area || shift == "hybrid-0.5") shift = "hybrid";
            Renderer r(test::gpuContext(),
                       shiftCheckGraph(shift, area ? "area" : "path", threshold), 48, 48, 3);
            r.loadScene(sourcePath(scene));
            int samples = 0, exact = 0, wrong = 0, reconnected = 0, neighbourOk = 0;
            for (int f = 0; f < 4; ++f) {
                r.frame();
                ImageData img = r.readOutput("check.check");
                for (uint32_t i = 0; i < img.width * img.height; ++i) {
                    const float* p = &img.pixels[i * 4];
                    if (p[3] < 0) continue;
                    // Pure reconnection cannot shift paths without a reconnection vertex at
                    // all (not even to their own pixel); the estimator gives them to the
                    // canonical sample.
                    int rc = int(p[3]) % 16;
                    if (shift == "reconnection" && rc == 0) continue;
                    ++samples;
                    if (std::abs(p[1] - p[0]) <= 1e-3 * p[0]) ++exact;
                    if (std::abs(p[1] - p[0]) > 1e-2 * p[0] && ++wrong <= 5)
                        ADD_FAILURE()
                            << scene << " " << shift << (area ? " area" : "") << ": stored " << p[0]
                            << " self-shift " << p[1] << " rc " << p[3];
                    if (rc > 0) ++reconnected;
                    if (p[2] > 0) ++neighbourOk;
                }
            }
            SCOPED_TRACE(std::string(scene) + " " + shift + (area ? " area" : "") + " threshold " +
                         std::to_string(threshold));
            ASSERT_GT(samples, 1000);
            // Float round-off only: segments of near-zero length or grazing angles (the
            // reconnection shift has no distance threshold) may differ by a little.
            EXPECT_EQ(wrong, 0);
            EXPECT_GE(exact, samples * 0.995);
            if (shift == "replay") {
                EXPECT_EQ(reconnected, 0);
            }
            if (shift == "hybrid") {
                EXPECT_GT(reconnected, samples / 2);
            }
            EXPECT_GT(neighbourOk, samples / 4);
        }
    }
}

// The counters the reuse passes expose to Lua and the inspector are consistent: attempts by
// kind, successes within attempts, and at least one ray per successful shift.
TEST(ReSTIRPT, ShiftCountersAreConsistent) {
    // Threshold 0.5: the spheres with alpha <= 0.2 are not rough, so some paths need replay.
    Renderer r(test::gpuContext(),
               loadGraph("restir_pt.json", {{"initial.roughnessThreshold", 0.5}}), 32, 32, 1);
    r.loadScene(sourcePath("scenes/glossy_spheres.json"));
    for (int f = 0; f < 3; ++f) r.frame();
    for (const char* name : {"temporal", "spatial"}) {
        SCOPED_TRACE(name);
        std::map<std::string, double> st;
        for (auto& p : r.graph().passes())
            if (p->name() == name) st = p->stats();
        ASSERT_TRUE(st.count("rays"));
        double attempts = st["shiftAttemptsReconnect"] + st["shiftAttemptsReplay"];
        double successes = st["shiftSuccessReconnect"] + st["shiftSuccessReplay"];
        EXPECT_GT(st["shiftAttemptsReconnect"], 0);
        EXPECT_GT(st["shiftAttemptsReplay"], 0);  // the glossy spheres need replay
        EXPECT_LE(st["shiftSuccessReconnect"], st["shiftAttemptsReconnect"]);
        EXPECT_LE(st["shiftSuccessReplay"], st["shiftAttemptsReplay"]);
        EXPECT_GT(successes, 0.25 * attempts);
        EXPECT_GE(st["rays"], successes);
        EXPECT_NEAR(st["reconnectShare"], st["shiftAttemptsReconnect"] / attempts, 1e-9);
    }
}

// reconnection_jacobian (solid angle, Lin et al. Eq. 17) and its primary-sample-space form
// against finite differences on 4096 random configurations, and the MIS weights of temporal (2-way
// balance) and spatial (defensive pairwise) reuse summing to 1 over all techniques for random
// targets incl. failed shifts.
TEST(ReSTIRPT, JacobianAndMisWeights) {
    const uint32_t n = 4096;
    json g = {{"name", "restir_jacobian"},
              {"passes",
               {{{"name", "k"},
                 {"type", "ComputePass"},
                 {"params",
                  {{"shader",
                    std::string(LOOM_SOURCE_DIR) + "/passes/restir_pt/tests/restir_jacobian.comp"},
                   {"outputs",
                    {{"results", {{"glsl", "Results"}, {"kind", "buffer"}, {"bytes", n * 16}}},
                     {"pss", {{"glsl", "PssResults"}, {"kind", "buffer"}, {"bytes", n * 8}}}}},
                   {"constants",
                    {{"count", {{"type", "uint"}, {"default", n}}},
                     {"seed", {{"type", "uint"}, {"default", 7}}}}},
                   {"dispatch", {n, 1, 1}}}}}}},
              {"edges", json::array()},
              {"outputs", {"k.results", "k.pss"}}};
    Renderer r(test::gpuContext(), RenderGraph::parse(g.dump(), "<test>"), 8, 8, 1);
    r.frame();
    std::vector<float> v(n * 4);
    r.gpu().downloadBuffer(*r.graph().outputBuffer("k.results"), v.data(), v.size() * 4);
    int checked = 0;
    double worst = 0;
    for (uint32_t i = 0; i < n; ++i) {
        float J = v[i * 4], Jfd = v[i * 4 + 1];
        if (Jfd >= 0) {
            ++checked;
            worst = std::max(worst, double(std::abs(J - Jfd) / Jfd));
        }
        EXPECT_NEAR(v[i * 4 + 2], 1.0f, 1e-5f) << "pairwise MIS weights, config " << i;
        EXPECT_NEAR(v[i * 4 + 3], 1.0f, 1e-5f) << "temporal MIS weights, config " << i;
    }
    EXPECT_GT(checked, int(n) / 2);
    EXPECT_LT(worst, 5e-3) << "reconnection Jacobian vs finite differences";

    // Primary-sample-space form (cosine-sampled predecessors).
    std::vector<float> pss(n * 2);
    r.gpu().downloadBuffer(*r.graph().outputBuffer("k.pss"), pss.data(), pss.size() * 4);
    int pssChecked = 0;
    double pssWorst = 0;
    for (uint32_t i = 0; i < n; ++i) {
        float J = pss[i * 2], Jfd = pss[i * 2 + 1];
        if (Jfd < 0) continue;
        ++pssChecked;
        pssWorst = std::max(pssWorst, double(std::abs(J - Jfd) / Jfd));
    }
    EXPECT_GT(pssChecked, int(n) / 4);
    EXPECT_LT(pssWorst, 1e-2) << "PSS reconnection Jacobian vs finite differences";
}

// Exploration (skipped unless asked for): LOOM_RESTIR_EXPLORE='{"scene":
// "scenes/cornell_box.json", "graph": "area_restir.json", "dt": 3, "overrides": {...}}' runs one
// comparison; LOOM_RESTIR_REGIONS=1 prints its fine regions (relative difference and z),
// LOOM_RESTIR_FINE=32 makes them single pixels, LOOM_RESTIR_SEQUENCES=96 goes deeper.
TEST(ReSTIRPT, Explore) {
    const char* e = std::getenv("LOOM_RESTIR_EXPLORE");
    if (!e) GTEST_SKIP() << "set LOOM_RESTIR_EXPLORE";
    json cfg = json::parse(e);
    scene::Scene s = scene::loadScene(sourcePath(cfg.value("scene", "scenes/cornell_box.json")));
    if (cfg.contains("aperture"))  // thin lens: {"aperture": 0.4, "focus": 5.5}
        s = withThinLens(s, cfg["aperture"].get<float>(), cfg.value("focus", 5.5f));
    auto c = compareWithReference(s, cfg.value("graph", "restir_pt.json"),
                                  cfg.value("overrides", json::object()), cfg.value("dt", 0.0f));
    EXPECT_TRUE(c.unbiased());
}
