// ReSTIRPTTemporal: temporal path reuse of ReSTIR PT (Lin et al. 2022). See README.md.
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "passes/restir_pt/PathReservoir.h"

namespace loom {

class ReSTIRPTTemporalPass : public Pass {
public:
    void reflect(PassReflection& r) const override { restir::reflectTemporalReuse(r); }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/restir_pt/temporal.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::Bindings b = restir::temporalReuseBindings(ctx, mCounters);
        KernelParams(*this, *mPipeline, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }
    void frameCompleted(gpu::Context& gpu) override { mCounters.read(gpu); }
    std::map<std::string, double> stats() const override { return mCounters.stats(); }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
    restir::ShiftCounters mCounters;
};

LOOM_REGISTER_PASS(ReSTIRPTTemporalPass, "ReSTIRPTTemporal",
                   "ReSTIR PT temporal reuse: shift last frame's path, generalized balance MIS");

}  // namespace loom
