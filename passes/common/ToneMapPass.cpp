// ToneMap: HDR radiance -> display values (exposure, operator, sRGB encode). See README.md.
#include <cmath>

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
        mPipeline = shaders.pipeline("passes/common/tonemap.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::PushConstants pc(*mPipeline);
        uint32_t size[2] = {ctx.width(), ctx.height()};
        std::string op = param<std::string>("operator");
        pc.setUints("frameSize", size, 2)
            .set("exposureScale", float(std::exp2(param<double>("exposure"))))
            .set("op", uint32_t(op == "clamp" ? 0 : op == "reinhard" ? 1 : 2))
            .set("srgb", uint32_t(param<bool>("srgb")));
        gpu::Bindings b;
        b.set("inputImage", ctx.texture("input")).set("outputImage", ctx.texture("output"));
        ctx.cmd().dispatchThreads(*mPipeline, b, &pc, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
};

LOOM_REGISTER_PASS(ToneMapPass, "ToneMap", "Exposure, tone curve and sRGB encoding for display");

}  // namespace loom
