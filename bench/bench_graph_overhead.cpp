// Per-pass overhead of the graph executor: frame time of chains of N empty ComputePasses.
// Prints GPU ms (timestamps) and wall ms per frame; the slope over N is the per-pass cost.
#include <chrono>
#include <cstdio>

#include "core/graph/Renderer.h"
#include "core/util/Log.h"

using namespace loom;

namespace {

std::unique_ptr<RenderGraph> emptyChain(int n) {
    json passes = json::array(), edges = json::array();
    for (int i = 0; i < n; ++i) {
        json params = {{"shader", std::string(LOOM_BENCH_DATA) + "/empty.comp"},
                       {"outputs", {{"out", {{"glsl", "target"}, {"format", "r32f"}}}}},
                       {"dispatch", json::array({1})}};
        passes.push_back({{"name", "p" + std::to_string(i)}, {"type", "ComputePass"},
                          {"params", params}});
        // Execution-only edges chain the passes so none is culled and order is fixed.
        if (i > 0) edges.push_back({"p" + std::to_string(i - 1), "p" + std::to_string(i)});
    }
    json g = {{"name", "empty_chain"}, {"passes", passes}, {"edges", edges},
              {"outputs", {"p" + std::to_string(n - 1) + ".out"}}};
    // Every pass's output must be consumed or marked, else it feeds nothing and is culled.
    for (int i = 0; i < n - 1; ++i) g["outputs"].push_back("p" + std::to_string(i) + ".out");
    return RenderGraph::parse(g.dump(), "<bench>");
}

}  // namespace

int main() {
    setLogLevel(LogLevel::Warning);
    auto gpu = gpu::Context::create();
    std::printf("device: %s\n", gpu->deviceInfo().name.c_str());
    std::printf("%8s %14s %14s %16s\n", "passes", "GPU ms/frame", "wall ms/frame", "wall us/pass");
    double wall1 = 0;
    for (int n : {1, 8, 32, 128}) {
        Renderer r(gpu, emptyChain(n), 64, 64);
        r.frames(5);  // warm up: compile pipelines, allocate
        const int frames = 50;
        double gpuMs = 0;
        auto t0 = std::chrono::steady_clock::now();
        for (int f = 0; f < frames; ++f) {
            r.frame();
            gpuMs += r.graph().frameGpuMs();
        }
        double wall = std::chrono::duration<double, std::milli>(
                          std::chrono::steady_clock::now() - t0).count() / frames;
        if (n == 1) wall1 = wall;
        std::printf("%8d %14.3f %14.3f %16.1f\n", n, gpuMs / frames, wall,
                    n > 1 ? (wall - wall1) / (n - 1) * 1000.0 : 0.0);
    }
    return 0;
}
