// GradientPathTracer: gradient-domain path tracing (Kettunen et al. 2015) with ReSTIR PT's
// hybrid shift; the G-PT baseline of gradient-domain ReSTIR PT (Wang et al. 2025). See
// README.md.
#include <algorithm>

#include "core/gpu/CounterBuffer.h"
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "passes/gradient_domain/GradientImages.h"
#include "passes/restir_pt/PathReservoir.h"

namespace loom {

class GradientPathTracerPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        gradient::reflectGradientImages(r, "MIS-weighted primal estimate");
        r.scratchBuffer("pixels")
            .bytesPerPixel(gradient::kGradientPixelBytes)
            .doc(
                "per pixel: weighted primal, four neighbour shares, four one-sided gradients, "
                "emission");
        r.param("samplesPerPixel", 1).range(1, 4096).doc("base paths per pixel per frame");
        r.param("maxBounces", 9).range(1, 14).doc("scattering events per path (PathTracer's)");
        r.paramEnum("shift", "hybrid", shaderEnum("SHIFT"))
            .doc("shift of the base path to the neighbours (ReSTIR PT's, Lin et al. Sec. 6)");
        r.param("roughnessThreshold", 0.2)
            .range(0, 1)
            .doc(
                "hybrid shift: both reconnection endpoints need linear roughness sqrt(alpha) above "
                "this");
        r.param("distanceThreshold", 0.1)
            .min(0)
            .doc("hybrid shift: minimum reconnection segment length");
        r.paramEnum("misHeuristic", "power", shaderEnum("MIS_HEURISTIC"))
            .doc("NEE/BSDF MIS inside a path, as PathTracer");
        r.param("motionBlur", false)
            .doc(
                "sample a shutter time per base path (replayed by its offset paths): camera motion "
                "blur");
        r.paramEnum("ablation", "none", {"none", "flipGradientSign", "halfWeights"})
            .doc(
                "biased variants the tests must detect: the gradient's sign flipped; MIS weights "
                "1/2 for every pair, also where the shift fails");
    }
    void compile(ShaderLibrary& shaders) override {
        mTrace = compileKernel(*this, shaders, "passes/gradient_domain/gpt.comp");
        mResolve.compile(*this, shaders);
    }
    void execute(ExecuteContext& ctx) override {
        auto rayCounter = mRayCounter.reset(ctx.gpu(), ctx.cmd());
        auto counters = mCounters.reset(ctx.gpu(), ctx.cmd());
        auto pixels = ctx.scratchBuffer("pixels");
        gpu::Bindings b;
        ctx.scene().bind(b);
        b.set("GradientPixels", pixels)
            .set("RayCounter", rayCounter)
            .set("RestirCounters", counters);
        // One dispatch per base path: each shifts its sub-paths four times, which keeps an
        // invocation's traversal steps far below lavapipe's loop limit (bvh.glsl).
        uint32_t spp = uint32_t(param<int>("samplesPerPixel"));
        for (uint32_t s = 0; s < spp; ++s) {
            if (s > 0) ctx.cmd().barrier();
            KernelParams(*this, *mTrace, ctx)
                .set("sampleIndex", s)
                .dispatch(ctx, b, ctx.width(), ctx.height());
        }
        ctx.cmd().barrier();
        mResolve.dispatch(*this, ctx, spp);
    }
    void frameCompleted(gpu::Context& gpu) override {
        mRayCounter.read(gpu);
        mCounters.read(gpu);
    }
    std::map<std::string, double> stats() const override {
        auto s = mCounters.stats();
        s["shiftRays"] = s["rays"];
        s["rays"] = mRayCounter[0] + s["shiftRays"];
        s["maxTraversalSteps"] = std::max<double>(mRayCounter[1], s["maxTraversalSteps"]);
        return s;
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mTrace;
    gradient::GradientPixelsResolve mResolve;
    gpu::CounterBuffer<2> mRayCounter{"RayCounter"};
    restir::ShiftCounters mCounters;
};

LOOM_REGISTER_PASS(GradientPathTracerPass, "GradientPathTracer",
                   "Gradient-domain path tracing (Kettunen 2015): base paths shifted to the 4 "
                   "neighbours by the hybrid shift, two-sided gradients and MIS primal");

}  // namespace loom
