// ReSTIRPTShade: the ReSTIR PT pixel estimate from the final path reservoirs. See README.md.
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"

namespace loom {

class ReSTIRPTShadePass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("reservoirs").doc("final reservoirs");
        r.inputBuffer("primary").doc("this frame's primary hits (ReSTIRPTInitial)");
        r.outputTexture("color", gpu::Format::RGBA32F).doc("radiance: primary emission + F W");
        r.param("emission", true).doc("add emission seen at the primary hit (and the environment)");
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/restir_pt/shade.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::Bindings b;
        ctx.scene().bind(b);
        b.set("ReservoirsIn", ctx.buffer("reservoirs"))
            .set("PrimaryIn", ctx.buffer("primary"))
            .set("colorImage", ctx.texture("color"));
        KernelParams(*this, *mPipeline, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
};

LOOM_REGISTER_PASS(ReSTIRPTShadePass, "ReSTIRPTShade",
                   "ReSTIR PT final shading: primary emission + reservoir estimate F W");

}  // namespace loom
