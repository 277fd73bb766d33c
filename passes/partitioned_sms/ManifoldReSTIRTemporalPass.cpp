// ManifoldReSTIRTemporal: temporal reuse of caustic reservoirs by the manifold shift (Hong et al.
// 2025 Sec. 5). See README.md.
#include "core/graph/RenderGraph.h"
#include "passes/partitioned_sms/ManifoldReuse.h"

namespace loom {

class ManifoldReSTIRTemporalPass : public ManifoldReusePass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("reservoirs").doc("this frame's reservoirs (PartitionedSMS.reservoirs)");
        r.inputBuffer("prevReservoirs")
            .previousFrame()
            .doc("last frame's final reservoirs: connect the last reuse pass's reservoirsOut");
        reflectManifoldReuse(r);
        r.param("confidenceCap", 20.0)
            .min(0)
            .doc("history's confidence clamped to this times the current one (paper: 20)");
        r.param("normalThreshold", 0.5).range(-1, 1).doc("reject history: normal cosine below");
        r.param("depthThreshold", 0.1).min(0).doc("reject history: relative depth above");
    }
    void execute(ExecuteContext& ctx) override {
        auto& k = kernel(ctx, "manifold_temporal.comp");
        gpu::Bindings b = bindings(ctx, "reservoirs");
        b.set("PrevReservoirs", ctx.buffer("prevReservoirs"));
        params(ctx, k).dispatch(ctx, b, ctx.width(), ctx.height());
    }
};

LOOM_REGISTER_PASS(ManifoldReSTIRTemporalPass, "ManifoldReSTIRTemporal",
                   "Temporal reuse of caustic reservoirs by the manifold shift (Hong et al. 2025 "
                   "Sec. 5): previous frame's sample at the reprojection, balance MIS");

}  // namespace loom
