// GradientAfterReSTIR: image gradients from a ReSTIR PT / Area ReSTIR frame's final reservoirs,
// each pixel's sample shifted to its four neighbours; the gradient-after-ReSTIR baseline of
// gradient-domain ReSTIR PT (Wang et al. 2025). See README.md.
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "passes/gradient_domain/GradientImages.h"
#include "passes/restir_pt/PathReservoir.h"

namespace loom {

class GradientAfterReSTIRPass : public restir::ShiftCountingPass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("reservoirs")
            .doc("final path reservoirs of the frame (ReSTIRPTSpatial.reservoirsOut)");
        r.inputBuffer("primary").doc("ReSTIRPTInitial.primary: the pixels' primary hits");
        gradient::reflectGradientImages(r, "the reservoirs' estimate F W");
        r.scratchBuffer("pixels")
            .bytesPerPixel(gradient::kGradientPixelBytes)
            .doc("per pixel: primal, four one-sided gradients, emission (gradient_pixels.glsl)");
        r.paramEnum("ablation", "none", {"none", "flipGradientSign"})
            .doc("biased variant the tests must detect: the gradient's sign flipped");
    }
    void compile(ShaderLibrary& shaders) override {
        mShift = compileKernel(*this, shaders, "passes/gradient_domain/gradient_after_restir.comp");
        mResolve.compile(*this, shaders);
    }
    void execute(ExecuteContext& ctx) override {
        auto counters = mCounters.reset(ctx.gpu(), ctx.cmd());
        auto pixels = ctx.scratchBuffer("pixels");
        gpu::Bindings b;
        ctx.scene().bind(b);
        b.set("ReservoirsIn", ctx.buffer("reservoirs"))
            .set("PrimaryIn", ctx.buffer("primary"))
            .set("GradientPixels", pixels)
            .set("RestirCounters", counters);
        KernelParams(*this, *mShift, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
        ctx.cmd().barrier();
        mResolve.dispatch(*this, ctx, 1u);
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mShift;
    gradient::GradientPixelsResolve mResolve;
};

LOOM_REGISTER_PASS(GradientAfterReSTIRPass, "GradientAfterReSTIR",
                   "Gradients after ReSTIR: each pixel's final reservoir sample shifted to its 4 "
                   "neighbours, balance weights on the targets, two-sided sums");

}  // namespace loom
