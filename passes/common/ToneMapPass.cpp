// ToneMap: HDR radiance -> display values (exposure, operator, sRGB encode). See README.md.
#include <cmath>

#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"

namespace loom {

class ToneMapPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputTexture("input", gpu::Format::RGBA32F).doc("linear HDR radiance");
        r.outputTexture("output", gpu::Format::RGBA32F).doc("display values in [0,1]");
        r.param("exposure", 0.0).range(-20, 20).doc("exposure in EV stops (scale 2^exposure)");
        r.paramEnum("operator", "aces", {"clamp", "reinhard", "aces"})
            .doc("tone curve: clamp, Reinhard 2002, or ACES (Narkowicz 2015 fit)");
        r.param("srgb", true).doc("encode with the sRGB transfer function");
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/common/tonemap.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::Bindings b;
        b.set("inputImage", ctx.texture("input")).set("outputImage", ctx.texture("output"));
        KernelParams(*this, *mPipeline, ctx)
            .set("exposureScale", float(std::exp2(param<double>("exposure"))))
            .dispatch(ctx, b, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
};

LOOM_REGISTER_PASS(ToneMapPass, "ToneMap", "Exposure, tone curve and sRGB encoding for display");

}  // namespace loom
