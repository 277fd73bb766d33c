// Spatiotemporal reuse of caustic reservoirs with the manifold shift (Hong et al. 2025 Sec. 5;
// passes/partitioned_sms/ManifoldReuse.cpp, shaders/lib/manifold/shift.glsl): the shift to
// its own pixel reproduces the sample, T^-1(T(x)) = x for accepted shifts, and psms with
// temporal and spatial reuse (static and moving camera) matches the reference path tracer and
// unbiased SMS. One reuse step's expectation, in closed form over enumerated solutions, equals
// the truth with the walk back and is off by up to a factor of two without it; with equal
// confidences that error moves energy between pixels and conserves it, which is why the paired
// image experiment at the end cannot see it in regions.
// Frames of one reuse sequence are correlated: the independent unit is a sequence (history
// reset, new seed), and its mean image is one sample (tests/support/ReuseComparison.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "core/scene/SceneLoader.h"
#include "passes/partitioned_sms/tests/PsmsTestScenes.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/KernelColumns.h"
#include "tests/support/RegionStats.h"
#include "tests/support/ReuseComparison.h"

namespace loom {
namespace {

using test::loadGraph;
using test::RegionStats;
using test::sourcePath;

// One sequence: history reset, `seed`, `frames` frames (frame f at time f dt); per port the
// mean luminance image.
std::vector<ImageData> sequenceMeans(Renderer& r, const std::vector<std::string>& ports,
                                     uint32_t seed, int frames, float dt) {
    r.setSeed(seed);
    r.reset();
    std::vector<ImageData> mean(ports.size());
    for (int f = 0; f < frames; ++f) {
        r.setTime(f * dt);
        r.frame();
        for (size_t p = 0; p < ports.size(); ++p) {
            ImageData img = r.readOutput(ports[p]);
            if (f == 0) {
                mean[p] = img;
            } else {
                for (size_t i = 0; i < img.pixels.size(); ++i) mean[p].pixels[i] += img.pixels[i];
            }
        }
    }
    for (auto& m : mean) {
        for (auto& v : m.pixels) v /= float(frames);
        m = test::toLuminance(m);
    }
    return mean;
}

// `sequences` runs of sequenceMeans; per port the statistics of each run's mean luminance over
// 2 x 2 regions, without the pixels `skip` marks (port 0 only).
std::vector<RegionStats> sequencePorts(std::unique_ptr<RenderGraph> g, const scene::Scene& scene,
                                       const std::vector<std::string>& ports, int sequences,
                                       int frames, float dt, uint32_t size, uint32_t seed,
                                       const std::vector<uint8_t>* skip = nullptr) {
    Renderer r(test::gpuContext(), std::move(g), size, size, 1);
    r.setScene(scene);
    std::vector<RegionStats> stats(ports.size(), RegionStats(2));
    for (int s = 0; s < sequences; ++s) {
        auto mean = sequenceMeans(r, ports, seed + 7919u * uint32_t(s), frames, dt);
        for (size_t p = 0; p < ports.size(); ++p) stats[p].add(mean[p], p == 0 ? skip : nullptr);
    }
    return stats;
}

// Pixels that see an emitter directly at any of the frame times (a 0-bounce path tracer), grown
// by a pixel. At 1 spp a small visible emitter covers a region through a handful of jittered
// hits of radiance 40 each; under camera motion that count read 3 sigma high at 2 of 4 seeds
// (README: open), in primary rays and emission that reuse does not touch. The path tracer's
// part with the caustic is compared in full by PartitionedSMS.Unbiased*.
std::vector<uint8_t> directEmitterPixels(const scene::Scene& scene, int frames, float dt,
                                         uint32_t size) {
    Renderer r(test::gpuContext(), test::ptGraph(16, 0), size, size, 1);
    r.setScene(scene);
    std::vector<uint8_t> seen(size * size, 0), grown(size * size, 0);
    for (int f = 0; f < frames; ++f) {
        r.setTime(f * dt);
        r.frame();
        ImageData img = r.readOutput("pt.color");
        for (uint32_t i = 0; i < size * size; ++i)
            if (img.pixels[i * img.channels] + img.pixels[i * img.channels + 1] +
                    img.pixels[i * img.channels + 2] >
                0.0f)
                seen[i] = 1;
    }
    for (uint32_t y = 0; y < size; ++y)
        for (uint32_t x = 0; x < size; ++x)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int u = int(x) + dx, v = int(y) + dy;
                    if (u >= 0 && v >= 0 && u < int(size) && v < int(size) && seen[v * size + u])
                        grown[y * size + x] = 1;
                }
    return grown;
}

// A large trial cap and 1024 presamples (the prior's tails, test_psms.cpp).
json largeTrialCap() {
    return {{"psms.maxTrials", 1000000}, {"psms.trialDispatches", 64}, {"prior.presamples", 1024}};
}

struct Agreement {
    double zPt, zSms;  // worst |z|: full image against PT, caustic against SMS
};

constexpr uint32_t kSize = 32;
// LOOM_PSMS_SEED: another seed for the estimator's sequences (a second, independent look).
uint32_t seedBase() {
    const char* e = std::getenv("LOOM_PSMS_SEED");
    return e ? uint32_t(std::atoi(e)) : 11u;
}
constexpr int kFrames = 8;

// graphFile's last reuse pass (`stage`) against PT (full image: stage.color, or colorPort) and
// SMS (caustic: stage.caustic), at the same frame times. A large trial cap and 1024 presamples
// (the prior's tails, test_psms.cpp). The full image leaves out the pixels that see the emitter
// directly (directEmitterPixels).
Agreement compareReuse(const std::string& sceneFile, const std::string& graphFile,
                       const std::string& stage, const json& overrides, float dt, int sequences,
                       const std::string& colorPort = "") {
    if (const char* k = std::getenv("LOOM_PSMS_FRAME_SCALE"))
        sequences *= std::max(1, std::atoi(k));
    auto scene = test::loadPsmsScene(sceneFile);
    json o = largeTrialCap();
    for (auto& [k, v] : overrides.items()) o[k] = v;
    auto skip = directEmitterPixels(scene, kFrames, dt, kSize);
    auto reuse =
        sequencePorts(loadGraph(graphFile, o), scene,
                      {colorPort.empty() ? stage + ".color" : colorPort, stage + ".caustic"},
                      sequences, kFrames, dt, kSize, seedBase(), &skip);
    // References per scene, camera motion and sequence count.
    static std::map<std::string, std::pair<RegionStats, RegionStats>> references;
    std::string key = sceneFile + "@" + std::to_string(dt) + "x" + std::to_string(sequences);
    auto ref = references.find(key);
    if (ref == references.end()) {
        auto pt = sequencePorts(test::ptGraph(16, 9), scene, {"pt.color"}, sequences, kFrames, dt,
                                kSize, 23, &skip);
        // The caustic at primary receivers, where psms estimates.
        auto sms = sequencePorts(loadGraph("sms.json", {{"sms.receiverDepth", 0}}), scene,
                                 {"sms.caustic"}, sequences, kFrames, dt, kSize, 29);
        ref = references.emplace(key, std::make_pair(pt[0], sms[0])).first;
    }
    const auto& [pt, sms] = ref->second;
    for (int i = 0; i < 4; ++i)
        std::printf(
            "%s region %d: full %.5f +- %.5f vs pt %.5f +- %.5f; caustic %.5f +- %.5f vs "
            "sms %.5f +- %.5f\n",
            graphFile.c_str(), i, reuse[0].mean(i * 3), std::sqrt(reuse[0].stderr2(i * 3)),
            pt.mean(i * 3), std::sqrt(pt.stderr2(i * 3)), reuse[1].mean(i * 3),
            std::sqrt(reuse[1].stderr2(i * 3)), sms.mean(i * 3), std::sqrt(sms.stderr2(i * 3)));
    Agreement a{test::maxZ(reuse[0], pt), test::maxZ(reuse[1], sms)};
    std::printf("%s %s dt %.1f: worst |z| %.2f against PT, %.2f against SMS\n", graphFile.c_str(),
                overrides.dump().c_str(), dt, a.zPt, a.zSms);
    return a;
}

// The shift on PartitionedSMS's samples of `frames` frames (manifold_shift_check.comp).
struct ShiftCheck {
    int samples = 0, own = 0, forward = 0, inverted = 0, forwardOff = 0, invertedOff = 0;
    double worstOwn = 0, worstOwnF = 0, worstInverse = 0;
};
ShiftCheck checkShifts(const scene::Scene& scene, uint32_t size, int frames,
                       bool expectExact = true) {
    test::TempDir dir("loom-manifold-shift");
    json g = loadGraph("psms_restir.json")->toJson();
    g["passes"].push_back(
        {{"name", "check"},
         {"type", "ComputePass"},
         {"params",
          {{"shader", sourcePath("passes/partitioned_sms/tests/manifold_shift_check.comp")},
           {"inputs", {{"reservoirs", {{"glsl", "ReservoirsIn"}, {"kind", "buffer"}}}}},
           {"outputs", {{"output", {{"glsl", "outputImage"}}}}}}}});
    g["edges"].push_back({"psms.reservoirs", "check.reservoirs"});
    g["outputs"] = {"check.output"};
    Renderer r(test::gpuContext(), RenderGraph::parse(g.dump(), dir / "graph.json"), size, size, 1);
    r.setScene(scene);
    ShiftCheck c;
    for (int f = 0; f < frames; ++f) {
        r.frame();
        ImageData out = r.readOutput("check.output");
        for (uint32_t i = 0; i < out.width * out.height; ++i) {
            const float* v = &out.pixels[i * 4];
            if (v[0] == -3.0f) continue;
            ++c.samples;
            if (v[0] >= 0.0f) {
                ++c.own;
                c.worstOwn = std::max(c.worstOwn, double(v[0]));
                c.worstOwnF = std::max(c.worstOwnF, double(v[1]));
            }
            if (v[2] >= 0.0f || v[2] == -2.0f) ++c.forward;
            if (v[2] >= 0.0f) {
                ++c.inverted;
                c.worstInverse = std::max(c.worstInverse, double(v[2]));
            }
            if (v[3] >= 0.0f || v[3] == -2.0f) ++c.forwardOff;
            if (v[3] >= 0.0f && v[3] < 1e-4f) ++c.invertedOff;
        }
    }
    std::printf(
        "%d samples: own pixel %d (worst |dx1| %.2g, |dF|/|F| %.2g); to q and back: %d of "
        "%d accepted shifts invert (worst %.2g); walk back off: %d of %d invert\n",
        c.samples, c.own, c.worstOwn, c.worstOwnF, c.inverted, c.forward, c.worstInverse,
        c.invertedOff, c.forwardOff);
    EXPECT_GT(c.samples, 200);
    if (!expectExact) return c;
    EXPECT_EQ(c.own, c.samples) << "the shift to its own pixel failed";
    EXPECT_LT(c.worstOwn, 1e-4);
    EXPECT_LT(c.worstOwnF, 1e-3);
    EXPECT_GT(c.forward, 50);
    EXPECT_EQ(c.inverted, c.forward) << "an accepted shift's inverse failed";
    EXPECT_LT(c.worstInverse, 1e-4);
    return c;
}

TEST(ManifoldShift, ReproducesTheSampleAtItsPixelAndInvertsWhereAccepted) {
    auto c = checkShifts(scene::loadScene(sourcePath("scenes/wavy_slab.json")), 48, 2);
    // Without the walk back some accepted shifts do not invert (measured 720 of 726 invert):
    // the scene holds shifts only the walk back rejects, so the assertion above fails when the
    // walk back is taken out of manifold_shift.
    EXPECT_LT(c.invertedOff, c.forwardOff) << "every shift inverts without the walk back: this "
                                              "scene cannot show what the walk back does";
}

// A rough (GGX alpha 0.1) curved mirror: the shift replays the sample's offset normals, so the
// shift to its own pixel reproduces the sample (F included) and accepted shifts invert. The
// check kernel is a ComputePass: it gets MANIFOLD_ROUGH_CASTERS as the passes do, by define.
TEST(ManifoldShift, ReplaysTheOffsetNormalsOfARoughMirror) {
    auto scene = test::loadPsmsScene("scenes/curved_mirror.json#rough");
    ::setenv("LOOM_SHADER_DEFINES", "MANIFOLD_ROUGH_CASTERS=1", 1);
    checkShifts(scene, 64, 12);
    // A shift that draws its own offsets instead (stream 0) does not reproduce the sample.
    ::setenv("LOOM_SHADER_DEFINES",
             "MANIFOLD_ROUGH_CASTERS=1;LOOM_TEST_SHIFT_OFFSETS_NOT_REPLAYED=1", 1);
    auto c = checkShifts(scene, 64, 12, false);
    ::unsetenv("LOOM_SHADER_DEFINES");
    EXPECT_TRUE(c.own < c.samples || c.worstOwnF > 1e-2)
        << "a shift that does not replay the offsets went unseen";
}

// 24 sequences per camera (CI time; this test was the suite's longest at 48, about 270 s warm).
TEST(ManifoldReSTIR, UnbiasedOnTheCurvedMirrorStaticAndMovingCamera) {
    for (float dt : {0.0f, 3.0f}) {
        auto a =
            compareReuse("scenes/curved_mirror.json", "psms_restir.json", "spatial", {}, dt, 24);
        EXPECT_LT(a.zPt, 3.0) << "dt " << dt;
        EXPECT_LT(a.zSms, 3.0) << "dt " << dt;
    }
}

// The full image with reuse everywhere (graphs/psms_restir_pt.json): ReSTIR PT leaves out the
// paths psms covers (ReSTIRPTInitial.coveredMaxChain, in its candidates and in every shift's
// replay) and the reused caustic is added. ReSTIR PT keeping the covered paths counts the
// caustic twice, which the same comparison must see.
TEST(ManifoldReSTIR, FullImageWithReSTIRPTUnbiasedMovingCamera) {
    // 24 sequences (CI time): at 48, |z| 1.17 against PT and 1.65 against SMS; twice, 10.4.
    auto a = compareReuse("scenes/curved_mirror.json", "psms_restir_pt.json", "causticSpatial", {},
                          3.0f, 24, "full.output");
    EXPECT_LT(a.zPt, 3.0);
    EXPECT_LT(a.zSms, 3.0);
    auto twice = compareReuse("scenes/curved_mirror.json", "psms_restir_pt.json", "causticSpatial",
                              {{"initial.coveredMaxChain", 0}}, 3.0f, 24, "full.output");
    EXPECT_GT(twice.zPt, 4.5) << "ReSTIR PT counting the caustic twice went unseen";
}

// Glossy casters under reuse: the rough curved mirror (GGX alpha 0.1), moving camera; the shifts
// replay each sample's offset normals (ManifoldShift.ReplaysTheOffsetNormalsOfARoughMirror).
TEST(ManifoldReSTIR, UnbiasedThroughARoughMirrorMovingCamera) {
    auto a = compareReuse("scenes/curved_mirror.json#rough", "psms_restir.json", "spatial", {},
                          3.0f, 16);
    EXPECT_LT(a.zPt, 3.0);
    EXPECT_LT(a.zSms, 3.0);
}

// Two refractions under reuse: the glass sphere raised past its caustic folds (finite
// variance; test_psms.cpp, UnbiasedThroughTheRaisedGlassSphere), moving camera. 32 sequences:
// at 16 the full image's region beside the sphere read |z| 2.92 against PT with a standard
// error of 0.00007, which 32 put at 0.00063 (rare paths through the sphere had not yet come;
// region 1 then agrees within 0.06, the worst region within 1.02 and 1.56 against SMS).
TEST(ManifoldReSTIR, UnbiasedThroughTheRaisedGlassSphereMovingCamera) {
    auto a = compareReuse("scenes/glass_sphere_raised.json", "psms_restir.json", "spatial", {},
                          3.0f, 32);
    EXPECT_LT(a.zPt, 3.0);
    EXPECT_LT(a.zSms, 3.0);
}

TEST(ManifoldReSTIR, UnbiasedThroughTheWavySlabMovingCamera) {
    auto a = compareReuse("scenes/wavy_slab.json", "psms_restir.json", "spatial", {}, 3.0f, 16);
    EXPECT_LT(a.zPt, 3.0);
    EXPECT_LT(a.zSms, 3.0);
}

TEST(ManifoldReSTIR, TemporalOnlyUnbiasedOnTheCurvedMirrorMovingCamera) {
    auto a = compareReuse("scenes/curved_mirror.json", "psms_temporal_only.json", "temporal", {},
                          3.0f, 16);
    EXPECT_LT(a.zPt, 3.0);
    EXPECT_LT(a.zSms, 3.0);
}

// Paired difference of two settings of one graph: per sequence (the same seeds for both, so
// both draw the same initial samples and differ only where the settings change a decision) the
// mean caustic luminance of `b` minus that of `a`, per pixel. E[b - a] != 0 means the two
// settings estimate different things: if `a` is unbiased (its own test), `b` is biased. The
// pairing cancels most of the caustic's variance, which unpaired comparisons with SMS cannot.
struct PairedSequences {
    std::vector<std::vector<double>> diff;  // [sequence][pixel]
    RegionStats a{2};                       // `a` alone, 2 x 2 regions
};
PairedSequences pairedDifference(const std::string& sceneFile, const std::string& graphFile,
                                 const std::string& port, const json& a, const json& b, float dt,
                                 int sequences) {
    auto scene = scene::loadScene(sceneFile[0] == '/' ? sceneFile : sourcePath(sceneFile));
    auto make = [&](const json& o) {
        json all = largeTrialCap();
        for (auto& [k, v] : o.items()) all[k] = v;
        auto r = std::make_unique<Renderer>(test::gpuContext(), loadGraph(graphFile, all), kSize,
                                            kSize, 1);
        r->setScene(scene);
        return r;
    };
    auto ra = make(a), rb = make(b);
    PairedSequences out;
    for (int s = 0; s < sequences; ++s) {
        uint32_t seed = seedBase() + 7919u * uint32_t(s);
        ImageData mean[2] = {sequenceMeans(*ra, {port}, seed, kFrames, dt)[0],
                             sequenceMeans(*rb, {port}, seed, kFrames, dt)[0]};
        out.a.add(mean[0]);
        if (const char* dump = std::getenv("LOOM_PSMS_ABLATION_DUMP"))  // per-sequence images
            for (int k = 0; k < 2; ++k)
                writeImage(std::string(dump) + "/" + std::to_string(s) + (k ? "_b" : "_a") + ".pfm",
                           mean[k]);
        std::vector<double> d(kSize * kSize);
        for (uint32_t i = 0; i < kSize * kSize; ++i)
            d[i] =
                double(mean[1].pixels[i * mean[1].channels]) - mean[0].pixels[i * mean[0].channels];
        out.diff.push_back(std::move(d));
    }
    return out;
}

// Sum over block x block pixel blocks (those with a nonzero spread) of z^2, z = the block's mean
// paired difference over its standard error, each sequence's difference multiplied by its sign.
double pairedChi2(const std::vector<std::vector<double>>& diff, const std::vector<int>& sign,
                  int block, int* blocks = nullptr, double* worstZ = nullptr) {
    int n = int(diff.size()), nb = int(kSize) / block, used = 0;
    double chi2 = 0.0, worst = 0.0;
    for (int by = 0; by < nb; ++by)
        for (int bx = 0; bx < nb; ++bx) {
            double sum = 0.0, sum2 = 0.0;
            for (int s = 0; s < n; ++s) {
                double v = 0.0;
                for (int y = by * block; y < (by + 1) * block; ++y)
                    for (int x = bx * block; x < (bx + 1) * block; ++x) v += diff[s][y * kSize + x];
                v *= sign[s];
                sum += v;
                sum2 += v * v;
            }
            double m = sum / n, var = (sum2 - n * m * m) / (n - 1);
            if (!(var > 1e-30)) continue;
            double z = m / std::sqrt(var / n);
            chi2 += z * z;
            worst = std::max(worst, std::abs(z));
            ++used;
        }
    if (blocks) *blocks = used;
    if (worstZ) *worstZ = worst;
    return chi2;
}

// The observed pairedChi2 against its sign-flip null (each sequence's difference negated at
// random, `flips` times): the fraction of flips at or above the observed value. Sign flips keep
// each sequence's sparsity, but assume a difference symmetric about 0: skewed differences of two
// unbiased settings fail it too (the control in DISABLED_WalkBackOffIsDetected), so this is a
// diagnostic, not a test of the mean.
double signFlipP(const std::vector<std::vector<double>>& diff, int block, int flips,
                 const char* what) {
    std::vector<int> sign(diff.size(), 1);
    int blocks = 0;
    double worst = 0.0;
    double obs = pairedChi2(diff, sign, block, &blocks, &worst);
    std::mt19937 rng(12345);
    std::vector<double> null;
    for (int f = 0; f < flips; ++f) {
        for (auto& v : sign) v = (rng() & 1u) ? 1 : -1;
        null.push_back(pairedChi2(diff, sign, block));
    }
    std::sort(null.begin(), null.end());
    double p = double(null.end() - std::lower_bound(null.begin(), null.end(), obs)) / flips;
    std::printf(
        "%s, %dx%d px blocks: %d blocks with a difference, worst |z| %.2f, sum z^2 %.1f; "
        "sign-flip null median %.1f, 99%% %.1f, max %.1f; p %.4f\n",
        what, block, block, blocks, worst, obs, null[flips / 2], null[flips * 99 / 100],
        null.back(), p);
    return p;
}

// ---------------------------------------------------------------------------------------------
// One reuse step's expectation, computed exactly (manifold_shift_queries.comp). At a fixed light
// point a receiver's caustic is a finite sum over its solutions, and a sampler whose contribution
// weight is unbiased per solution (psms's K / P(C), SMS's) makes every reuse estimator's
// expectation a finite sum too. For pixel c with one spatial neighbour q, pairwise MIS
// (manifold_spatial.comp, confidences 1):
//   E = sum_{y in S_c} m_c(y) p_c(y) + sum_{x in S_q, T(x) accepted} m_q(T x) p_c(T x),
//   m_c(y) = p_c(y) / (p_c(y) + p_q(T^-1 y)),  m_q(T x) = p_q(x) / (p_q(x) + p_c(T x)),
// against the truth sum_{y in S_c} p_c(y). They are equal exactly when the accepted shifts are
// a bijection whose inverse is the reverse shift, which is what the walk back enforces. S_c and
// S_q come from dense seed grids, closed under every shift the test runs (a solution a shift
// reaches joins its receiver's set), so a solution the grid missed cannot fake a bias.

struct ShiftQuery {
    glm::vec3 from, to;  // receiver points on the floor (traced from 0.5 above)
    glm::vec3 x1;        // the source solution's first vertex, or a seed point
    bool bijective;
    int iterations;
};
struct ShiftAnswer {
    glm::vec3 x1;
    bool ok;
    double p;  // luminance(f T Le G) at the destination
};

std::vector<ShiftAnswer> runShiftQueries(const scene::Scene& scene,
                                         const std::vector<ShiftQuery>& q, uint32_t light,
                                         glm::vec2 uv, uint32_t caster) {
    const uint32_t width = uint32_t(std::min<size_t>(q.size(), 1024));
    const uint32_t blocks = uint32_t((q.size() + width - 1) / width);
    ImageData in;
    in.width = width;
    in.height = blocks * 6;
    in.channels = 4;
    in.pixels.assign(size_t(in.width) * in.height * 4, 0.0f);
    auto put = [&](size_t k, int r, glm::vec4 v) {
        size_t i = (size_t(k / width) * 6 + r) * width + k % width;
        for (int c = 0; c < 4; ++c) in.pixels[i * 4 + c] = v[c];
    };
    for (size_t k = 0; k < q.size(); ++k) {
        put(k, 0, glm::vec4(q[k].from + glm::vec3(0, 0.5f, 0), 0));
        put(k, 1, glm::vec4(0, -1, 0, q[k].bijective ? 1.0f : 0.0f));
        put(k, 2, glm::vec4(q[k].to + glm::vec3(0, 0.5f, 0), 0));
        put(k, 3, glm::vec4(0, -1, 0, float(q[k].iterations)));
        put(k, 4, glm::vec4(q[k].x1, float(light)));
        put(k, 5, glm::vec4(uv, float(caster), -1.0f));
    }
    ImageData out =
        test::runKernelImage(scene, "passes/partitioned_sms/tests/manifold_shift_queries.comp", in);
    std::vector<ShiftAnswer> a(q.size());
    for (size_t k = 0; k < q.size(); ++k) {
        size_t i = (size_t(k / width) * 6) * width + k % width;
        const float* r0 = &out.pixels[i * out.channels];
        const float* r1 = &out.pixels[(i + width) * out.channels];
        a[k] = {glm::vec3(r0[0], r0[1], r0[2]), r0[3] > 0.5f, double(r1[3])};
    }
    return a;
}

struct ReuseStepBias {
    double worstOn = 0, worstOff = 0;  // worst |E - truth| / truth over pairs
    double netOn = 0, netOff = 0;      // sum over pairs of E - truth, over sum of truth
    int pairs = 0, biasedOff = 0;      // pairs with a caustic; of which off is > 1e-3 off
    int nonInjective = 0, solutions = 0;
};

// Receivers on a floor lattice (spacing `step`), pairs of lattice neighbours `offsets` apart
// (both ways), light point (light, uv), solutions enumerated from a grid x grid seed lattice
// over the square [-extent, extent]^2 at height seedY, 20 Newton steps; the shifts as the passes
// run them (5 steps).
std::vector<ReuseStepBias> reuseStepBias(const scene::Scene& scene, uint32_t caster, uint32_t light,
                                         glm::vec2 uv, glm::vec2 lo, glm::ivec2 count, float step,
                                         const std::vector<glm::ivec2>& offsets, float seedY,
                                         float extent, int grid,
                                         const std::vector<double>& confidences) {
    struct Solution {
        glm::vec3 x1;
        double p;
    };
    const int nr = count.x * count.y;
    std::vector<glm::vec3> rx(nr);
    for (int j = 0; j < count.y; ++j)
        for (int i = 0; i < count.x; ++i)
            rx[j * count.x + i] = glm::vec3(lo.x + step * i, 0.0f, lo.y + step * j);
    std::vector<std::vector<Solution>> sol(nr);
    auto add = [&](int r, glm::vec3 x1, double p) {
        for (auto& s : sol[r])
            if (glm::length(s.x1 - x1) < 2e-4f) return false;
        sol[r].push_back({x1, p});
        return true;
    };
    // Enumeration: one solve per seed at every receiver.
    {
        std::vector<ShiftQuery> q;
        for (int r = 0; r < nr; ++r)
            for (int j = 0; j < grid; ++j)
                for (int i = 0; i < grid; ++i)
                    q.push_back({rx[r], rx[r],
                                 glm::vec3(-extent + 2 * extent * (i + 0.5f) / grid, seedY,
                                           -extent + 2 * extent * (j + 0.5f) / grid),
                                 false, 20});
        auto a = runShiftQueries(scene, q, light, uv, caster);
        for (size_t k = 0; k < q.size(); ++k)
            if (a[k].ok && a[k].p > 0) add(int(k / (grid * grid)), a[k].x1, a[k].p);
    }
    struct Pair {
        int c, q;
    };
    std::vector<Pair> pairs;
    for (int r = 0; r < nr; ++r)
        for (auto o : offsets) {
            int i = r % count.x + o.x, j = r / count.x + o.y;
            if (i < 0 || j < 0 || i >= count.x || j >= count.y) continue;
            pairs.push_back({r, j * count.x + i});
            pairs.push_back({j * count.x + i, r});
        }
    // Shifts of every solution of q to c (on, off): key (pair, solution, bijective).
    std::map<std::tuple<int, int, bool>, ShiftAnswer> shifted;
    for (int round = 0; round < 4; ++round) {
        std::vector<ShiftQuery> q;
        std::vector<std::tuple<int, int, bool>> keys;
        for (int pi = 0; pi < int(pairs.size()); ++pi)
            for (int si = 0; si < int(sol[pairs[pi].q].size()); ++si)
                for (bool b : {true, false})
                    if (!shifted.count({pi, si, b})) {
                        q.push_back(
                            {rx[pairs[pi].q], rx[pairs[pi].c], sol[pairs[pi].q][si].x1, b, 5});
                        keys.push_back({pi, si, b});
                    }
        if (q.empty()) break;
        auto a = runShiftQueries(scene, q, light, uv, caster);
        bool grew = false;
        for (size_t k = 0; k < q.size(); ++k) {
            shifted[keys[k]] = a[k];
            if (a[k].ok && a[k].p > 0) grew |= add(pairs[std::get<0>(keys[k])].c, a[k].x1, a[k].p);
        }
        if (!grew) break;
    }
    // The pair (c, q) and its reverse (q, c) are consecutive entries.
    std::map<std::pair<int, int>, int> index;
    for (int pi = 0; pi < int(pairs.size()); ++pi) index[{pairs[pi].c, pairs[pi].q}] = pi;
    std::vector<ReuseStepBias> result;
    for (double Mq : confidences) {  // M_q / M_c
        ReuseStepBias out;
        for (auto& s : sol) out.solutions += int(s.size());
        double truthSum = 0;
        for (int pi = 0; pi < int(pairs.size()); ++pi) {
            const auto& [c, qn] = pairs[pi];
            int rev = index.at({qn, c});
            double truth = 0;
            for (auto& y : sol[c]) truth += y.p;
            if (!(truth > 0)) continue;
            ++out.pairs;
            truthSum += truth;
            for (bool b : {true, false}) {
                double e = 0;
                for (int yi = 0; yi < int(sol[c].size()); ++yi) {
                    const auto& y = sol[c][yi];
                    auto it = shifted.find({rev, yi, b});  // y to q
                    double pq = it != shifted.end() && it->second.ok ? it->second.p : 0.0;
                    e += y.p * y.p / (y.p + Mq * pq);
                }
                std::vector<glm::vec3> images;
                for (int xi = 0; xi < int(sol[qn].size()); ++xi) {
                    const auto& t = shifted.at({pi, xi, b});
                    if (!t.ok || !(t.p > 0)) continue;
                    double px = sol[qn][xi].p;
                    e += t.p * Mq * px / (Mq * px + t.p);
                    if (!b) {
                        for (auto& o : images)
                            if (glm::length(o - t.x1) < 2e-4f) ++out.nonInjective;
                        images.push_back(t.x1);
                    }
                }
                double rel = (e - truth) / truth;
                double& worst = b ? out.worstOn : out.worstOff;
                worst = std::max(worst, std::abs(rel));
                (b ? out.netOn : out.netOff) += e - truth;
                if (!b && std::abs(rel) > 1e-3) ++out.biasedOff;
            }
        }
        out.netOn /= truthSum;
        out.netOff /= truthSum;
        result.push_back(out);
    }
    return result;
}

// The bumpy mirror: an 8 x 8 floor lattice across the caustic (spacing 0.3, about 6 pixels of
// the 32^2 test images), neighbours 1 and 2 steps apart both ways, both light triangles' centres,
// confidences equal (spatial reuse) and 20 : 1 (temporal history against a new sample). 29 s.
// Measured (2026-12-07): walk back on, worst 3.7e-7 / 1.5e-4 (equal) and 1.6e-6 / 6.0e-4 (20 : 1):
// the solver's tolerance; off, worst 1.13 / 0.67 and 1.93 / 1.76, 131 - 145 of about 290 pairs
// biased, net 0 (equal, the identity below) and +3.1 % / +2.1 % (20 : 1).
TEST(ManifoldReuse, OneStepIsExactlyUnbiasedWithTheWalkBackAndNotWithout) {
    auto scene = scene::loadScene(sourcePath("scenes/bumpy_mirror.json"));
    uint32_t mirror = 0;
    while (scene.shapes[mirror].name != "mirror") ++mirror;
    int grid = 32;
    if (const char* g = std::getenv("LOOM_REUSE_STEP_GRID")) grid = std::atoi(g);
    glm::ivec2 count(8, 8);
    if (const char* g = std::getenv("LOOM_REUSE_STEP_COUNT")) count = glm::ivec2(std::atoi(g));
    float step = 0.3f;
    if (const char* g = std::getenv("LOOM_REUSE_STEP")) step = float(std::atof(g));
    glm::vec2 lo(-1.2f, -1.2f);
    const std::vector<double> confidences = {1.0, 20.0};
    for (uint32_t light : {0u, 1u}) {
        auto r = reuseStepBias(scene, mirror, light, glm::vec2(1.0f / 3.0f), lo, count, step,
                               {{1, 0}, {0, 1}, {2, 0}, {0, 2}}, 1.8f, 0.85f, grid, confidences);
        for (size_t k = 0; k < r.size(); ++k) {
            const auto& b = r[k];
            std::printf(
                "light %u, M_q / M_c = %g: %d solutions at %d receivers, %d pairs with a caustic. "
                "Walk back on: worst |E - truth| / truth %.2e, net %+.2e. Off: worst %.3f, net "
                "%+.2e, %d pairs biased (> 1e-3), %d non-injective shifts\n",
                light, confidences[k], b.solutions, count.x * count.y, b.pairs, b.worstOn, b.netOn,
                b.worstOff, b.netOff, b.biasedOff, b.nonInjective);
            EXPECT_GT(b.pairs, 20);
            // Two converged solves of one solution differ within the solver's threshold (1e-5);
            // their targets then differ by about 1e-4, amplified by the confidence ratio.
            EXPECT_LT(b.worstOn, 2e-3) << "one reuse step is biased with the walk back";
            EXPECT_GT(b.worstOff, 0.05) << "without the walk back no pair is biased: this setup "
                                           "cannot show what the walk back does";
        }
        // Equal confidences: what one pixel gains from a non-bijective shift its neighbour
        // loses (the terms p_c p_q / (p_c + p_q) of the pair and of its reverse cancel), so
        // the total over both is exact with or without the walk back.
        EXPECT_LT(std::abs(r[0].netOff), 1e-9);
    }
}

// Disabled: an experiment (about 6 min per 64 sequences), open (issue 16). Walk back off minus
// on, paired, on the bumpy mirror with 4 neighbours in 3 px (LOOM_PSMS_ABLATION_PARAMS to
// change). It asks for the 2 x 2 regions' |z| > 5 and so far fails: measured 1.49 (64 sequences),
// 1.50 at paper defaults and 0.98 on a rippled mirror (README, "The walk-back ablation in the
// image"). The per-block sign-flip statistics it prints are not calibrated: the control
// LOOM_PSMS_ABLATION_B='{"spatial.mis": "defensivePairwise"}' (two unbiased settings) is rejected
// per pixel as strongly as walk back off. Env: _SEQUENCES, _SCENE (a path under the source tree,
// or absolute), _PARAMS (JSON overrides for both), _B (for the second), _DT (the frame time
// step, 0: static camera), _DUMP (a folder for per-sequence images: s_a.pfm, s_b.pfm). Run
// with --gtest_also_run_disabled_tests.
TEST(ManifoldReSTIR, DISABLED_WalkBackOffIsDetected) {
    int sequences = 64;
    if (const char* s = std::getenv("LOOM_PSMS_ABLATION_SEQUENCES")) sequences = std::atoi(s);
    std::string sceneFile = "scenes/bumpy_mirror.json";
    if (const char* s = std::getenv("LOOM_PSMS_ABLATION_SCENE")) sceneFile = s;
    json a = {{"spatial.radius", 3}, {"spatial.neighbours", 4}};
    if (const char* s = std::getenv("LOOM_PSMS_ABLATION_PARAMS")) a = json::parse(s);
    json b = {{"temporal.bijectivity", false}, {"spatial.bijectivity", false}};
    if (const char* s = std::getenv("LOOM_PSMS_ABLATION_B")) b = json::parse(s);
    json bAll = a;
    for (auto& [k, v] : b.items()) bAll[k] = v;
    float dt = 0.0f;  // frame time step along the scene's camera path: 0 static, 3 moving
    if (const char* s = std::getenv("LOOM_PSMS_ABLATION_DT")) dt = float(std::atof(s));
    auto paired =
        pairedDifference(sceneFile, "psms_restir.json", "spatial.caustic", a, bAll, dt, sequences);
    std::printf("%s, %d sequences: a = %s, b = a + %s\n", sceneFile.c_str(), sequences,
                a.dump().c_str(), b.dump().c_str());
    RegionStats d(2);
    for (auto& img : paired.diff) {
        ImageData di;
        di.width = di.height = kSize;
        di.channels = 3;
        di.pixels.resize(kSize * kSize * 3);
        for (uint32_t i = 0; i < kSize * kSize; ++i)
            for (int c = 0; c < 3; ++c) di.pixels[i * 3 + c] = float(img[i]);
        d.add(di);
    }
    for (int i = 0; i < 4; ++i)
        std::printf("region %d: a %.5f +- %.5f, b - a %+.6f +- %.6f\n", i, paired.a.mean(i * 3),
                    std::sqrt(paired.a.stderr2(i * 3)), d.mean(i * 3), std::sqrt(d.stderr2(i * 3)));
    double worst = 0.0;
    for (int i = 0; i < 4; ++i)
        worst = std::max(worst, std::abs(d.mean(i * 3)) / std::sqrt(d.stderr2(i * 3) + 1e-30));
    for (int block : {1, 2, 4, 8}) signFlipP(paired.diff, block, 1000, "b - a");
    EXPECT_GT(worst, 5.0) << "reuse without the walk back went unseen in 2 x 2 regions";
}

// Control for the moving-camera comparisons: psms without reuse, at the same frame times.
TEST(ManifoldReSTIR, DISABLED_ControlPsmsAloneMovingCamera) {
    auto a = compareReuse("scenes/curved_mirror.json", "psms.json", "psms", {}, 3.0f, 48);
    EXPECT_LT(a.zPt, 3.0);
    EXPECT_LT(a.zSms, 3.0);
}
}  // namespace
}  // namespace loom
