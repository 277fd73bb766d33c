// @PASS@: one stage of the @FAMILY@ family. See README.md.
// Parameters are declared once in reflect(); KernelParams fills the kernel's members of the
// same names (enums as indices named by the generated MODE_* defines).
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"

namespace loom {

class @PASS@Pass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputTexture("input", gpu::Format::RGBA32F).doc("image to process");
        r.outputTexture("output", gpu::Format::RGBA32F).doc("gain x input (or x input^2)");
        r.param("gain", 1.0).min(0).doc("scale applied to every channel");
        r.paramEnum("mode", "scale", {"scale", "square"})
            .doc("scale: gain x input; square: gain x input^2");
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/@FAMILY@/@KERNEL@.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::Bindings b;
        b.set("inputImage", ctx.texture("input")).set("outputImage", ctx.texture("output"));
        KernelParams(*this, *mPipeline, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
};

LOOM_REGISTER_PASS(@PASS@Pass, "@PASS@", "@FAMILY@: gain x input (template pass)");

}  // namespace loom
