#pragma once
// The images every gradient estimator of this family writes (GradientPathTracer,
// GradientAfterReSTIR, PairedPixelResolve), declared once: what PoissonReconstruct and the
// graphs' emission add-back read.
#include <memory>
#include <string>

#include "core/graph/KernelParams.h"
#include "core/graph/Pass.h"
#include "core/graph/RenderGraph.h"

namespace loom::gradient {

// primal: what this estimator's primal is (the emission at the primary hit is left out).
inline void reflectGradientImages(PassReflection& r, const std::string& primal) {
    r.outputTexture("primal", gpu::Format::RGBA32F)
        .doc(primal + ", without the emission seen at the primary hit");
    r.outputTexture("dx", gpu::Format::RGBA32F)
        .doc("estimate of I(p + e_x) - I(p), without that emission; 0 in the last column");
    r.outputTexture("dy", gpu::Format::RGBA32F)
        .doc("estimate of I(p + e_y) - I(p), without that emission; 0 in the last row");
    r.outputTexture("direct", gpu::Format::RGBA32F)
        .doc(
            "emission seen at the primary hit (environment on a miss), added back after the solve");
    r.outputTexture("color", gpu::Format::RGBA32F).optional().doc("primal + direct");
}

// GradientPixel (gradient_pixels.glsl): the per-pixel sums G-PT and gradient after ReSTIR write.
constexpr uint64_t kGradientPixelBytes = 10 * 16;

// gpt_resolve.comp: the images of reflectGradientImages from those sums (scratch `pixels`).
class GradientPixelsResolve {
public:
    void compile(const Pass& pass, ShaderLibrary& shaders) {
        for (int color = 0; color < 2; ++color)
            mPipeline[color] =
                compileKernel(pass, shaders, "passes/gradient_domain/gpt_resolve.comp",
                              {{"HAS_COLOR", color ? "1" : "0"}});
    }
    // samplesPerPixel: the sums' sample count (they are divided by it).
    void dispatch(const Pass& pass, ExecuteContext& ctx, uint32_t samplesPerPixel) {
        bool color = ctx.has("color");
        gpu::Bindings b;
        b.set("GradientPixels", ctx.scratchBuffer("pixels"))
            .set("primalImage", ctx.texture("primal"))
            .set("dxImage", ctx.texture("dx"))
            .set("dyImage", ctx.texture("dy"))
            .set("directImage", ctx.texture("direct"));
        if (color) b.set("colorImage", ctx.texture("color"));
        KernelParams(pass, *mPipeline[color], ctx)
            .set("samplesPerPixel", samplesPerPixel)
            .dispatch(ctx, b, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline[2];
};

}  // namespace loom::gradient
