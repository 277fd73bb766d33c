// ManifoldReSTIRSpatial: spatial reuse of caustic reservoirs by the manifold shift (Hong et al.
// 2025 Sec. 5). See README.md.
#include "core/graph/RenderGraph.h"
#include "passes/partitioned_sms/ManifoldReuse.h"

namespace loom {

class ManifoldReSTIRSpatialPass : public ManifoldReusePass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("reservoirs").doc("reservoirs to reuse between (after temporal reuse)");
        reflectManifoldReuse(r);
        r.param("neighbours", 1).range(1, 4).doc("neighbours (paper: 1)");
        r.param("radius", 30.0).min(1).doc("neighbour disk radius, pixels (paper: 30)");
        r.param("normalThreshold", 0.5).range(-1, 1).doc("reject neighbours: normal cosine below");
        r.param("depthThreshold", 0.1).min(0).doc("reject neighbours: relative depth above");
        r.paramEnum("mis", "pairwise", {"pairwise", "defensivePairwise"})
            .doc("resampling MIS: pairwise (paper), or defensive pairwise");
    }
    void execute(ExecuteContext& ctx) override {
        auto& k = kernel(ctx, "manifold_spatial.comp");
        gpu::Bindings b = bindings(ctx, "reservoirs");
        params(ctx, k).dispatch(ctx, b, ctx.width(), ctx.height());
    }
};

LOOM_REGISTER_PASS(ManifoldReSTIRSpatialPass, "ManifoldReSTIRSpatial",
                   "Spatial reuse of caustic reservoirs by the manifold shift (Hong et al. 2025 "
                   "Sec. 5): 1 neighbour in 30 px, pairwise MIS");

}  // namespace loom
