#pragma once
// Statistical comparison of a reuse estimator (ReSTIR PT, Area ReSTIR, reservoir splatting)
// against the reference path tracer. Frames of one ReSTIR sequence are correlated through
// temporal and spatial reuse, so the independent unit is a whole sequence (history reset, new
// seed): each sequence's mean image is one sample, and the spread over sequences gives the
// standard error. The comparison is against a path-traced reference rendered at the same frame
// times, in luminance, on 2x2 regions (|z| < 3) and on 8x8 regions (4x4-pixel blocks at 32x32:
// |z| < 4.5, Bonferroni for 64 comparisons; a bias confined to one block is diluted 16x in the
// coarse regions). motionBlur: the reference samples the shutter (PathTracer.motionBlur).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>

#include "core/graph/Renderer.h"
#include "core/scene/SceneLoader.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/KernelColumns.h"
#include "tests/support/RegionStats.h"

namespace loom::test {

// graphs/<file>, parameters overridden ("pass.param": value).
inline std::unique_ptr<RenderGraph> loadGraph(const std::string& file, const json& overrides = {}) {
    auto g = RenderGraph::load(sourcePath("graphs/" + file));
    for (auto& [key, value] : overrides.items()) g->setParam(key, value);
    return g;
}

inline std::unique_ptr<RenderGraph> ptGraph(int spp, int maxBounces, bool motionBlur = false) {
    json g = {
        {"name", "pt_reference"},
        {"passes",
         {{{"name", "pt"},
           {"type", "PathTracer"},
           {"params",
            {{"samplesPerPixel", spp}, {"maxBounces", maxBounces}, {"motionBlur", motionBlur}}}}}},
        {"edges", json::array()},
        {"outputs", {"pt.color"}}};
    return RenderGraph::parse(g.dump(), "<test>");
}

// A scene with its camera turned into a thin lens (aperture radius, focus distance).
inline scene::Scene withThinLens(scene::Scene s, float aperture, float focus) {
    s.camera.type = scene::CameraType::ThinLens;
    s.camera.apertureRadius = aperture;
    s.camera.focusDistance = focus;
    return s;
}

inline ImageData toLuminance(const ImageData& img) {
    ImageData out = img;
    for (uint32_t i = 0; i < img.width * img.height; ++i) {
        const float* p = &img.pixels[i * img.channels];
        float y = 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
        for (uint32_t c = 0; c < 3; ++c) out.pixels[i * img.channels + c] = y;
    }
    return out;
}

// Frames of the graph's `ports`, luminance: each frame is an independent estimate.
inline std::vector<RegionStats> frameStats(std::unique_ptr<RenderGraph> graph,
                                           const scene::Scene& scene,
                                           const std::vector<std::string>& ports, int frames,
                                           int regions, uint32_t size, uint32_t seed) {
    Renderer r(gpuContext(), std::move(graph), size, size, 1);
    r.setScene(scene);
    r.setSeed(seed);
    std::vector<RegionStats> stats(ports.size(), RegionStats(regions));
    for (int f = 0; f < frames; ++f) {
        r.frame();
        for (size_t p = 0; p < ports.size(); ++p) {
            stats[p].add(toLuminance(r.readOutput(ports[p])));
        }
    }
    return stats;
}

// `sequences` independent runs of `frames` frames each (frame f at time t0 + f * dt); each
// run's mean image is one sample of the returned statistics (coarse, fine regions).
constexpr int kCoarseRegions = 2;
// LOOM_RESTIR_FINE changes the fine regions for exploration (the threshold stays Bonferroni for
// 64; e.g. 32 gives single pixels at 32x32).
inline const int kFineRegions =
    std::getenv("LOOM_RESTIR_FINE") ? std::atoi(std::getenv("LOOM_RESTIR_FINE")) : 8;
constexpr double kCoarseZ = 3.0, kFineZ = 4.5;

inline std::pair<RegionStats, RegionStats> sequenceStats(Renderer& r, const std::string& port,
                                                         int sequences, int frames, float dt) {
    std::pair<RegionStats, RegionStats> stats{RegionStats(kCoarseRegions),
                                              RegionStats(kFineRegions)};
    for (int s = 0; s < sequences; ++s) {
        r.setSeed(1000u + 7919u * uint32_t(s));
        r.reset();
        ImageData mean;
        for (int f = 0; f < frames; ++f) {
            r.setTime(f * dt);
            r.frame();
            ImageData img = r.readOutput(port);
            if (f == 0) {
                mean = img;
            } else {
                for (size_t i = 0; i < img.pixels.size(); ++i) mean.pixels[i] += img.pixels[i];
            }
        }
        for (auto& v : mean.pixels) v /= float(frames);
        ImageData y = toLuminance(mean);
        stats.first.add(y);
        stats.second.add(y);
    }
    return stats;
}

struct Comparison {
    double z = 0, restir = 0, reference = 0;  // coarse regions: worst |z| and its means
    double zFine = 0;                         // fine regions: worst |z|
    bool unbiased() const { return z < kCoarseZ && zFine < kFineZ; }
};

// LOOM_RESTIR_SEQUENCES raises the sequence count for a deeper (slower) check than CI's.
inline int defaultSequences() {
    const char* e = std::getenv("LOOM_RESTIR_SEQUENCES");
    return e ? std::max(4, std::atoi(e)) : 24;
}

inline Comparison compareWithReference(const scene::Scene& scene, const std::string& graphFile,
                                       const json& overrides, float dt, int size = 32,
                                       int sequences = defaultSequences(), int frames = 8,
                                       bool motionBlur = false) {
    Comparison c;
    std::pair<RegionStats, RegionStats> restir{RegionStats(1), RegionStats(1)}, reference = restir;
    {
        Renderer r(test::gpuContext(), loadGraph(graphFile, overrides), size, size, 1);
        r.setScene(scene);
        restir = sequenceStats(r, "shade.color", sequences, frames, dt);
    }
    {
        Renderer r(test::gpuContext(), ptGraph(8, 9, motionBlur), size, size, 2);
        r.setScene(scene);
        reference = sequenceStats(r, "pt.color", sequences, frames, dt);
    }
    c.z = maxZ(restir.first, reference.first, &c.restir, &c.reference);
    c.zFine = maxZ(restir.second, reference.second);
    if (std::getenv("LOOM_RESTIR_REGIONS")) {  // diagnostics: fine regions, relative difference
        for (int y = 0; y < kFineRegions; ++y) {
            for (int x = 0; x < kFineRegions; ++x) {
                size_t i = size_t(y * kFineRegions + x) * 3;
                double a = restir.second.mean(i), b = reference.second.mean(i);
                double z = (a - b) / std::sqrt(restir.second.stderr2(i) +
                                               reference.second.stderr2(i) + 1e-30);
                std::printf(" %+6.1f%%(%+4.1f)", 100.0 * (a - b) / std::max(b, 1e-9), z);
            }
            std::printf("\n");
        }
    }
    std::printf("[ restir  ] %s %s: max |z| %.2f (%.5g vs %.5g), fine regions %.2f\n",
                graphFile.c_str(), overrides.dump().c_str(), c.z, c.restir, c.reference, c.zFine);
    return c;
}

inline Comparison compareWithReference(const std::string& scenePath, const std::string& graphFile,
                                       const json& overrides, float dt) {
    return compareWithReference(scene::loadScene(scenePath), graphFile, overrides, dt);
}

}  // namespace loom::test
