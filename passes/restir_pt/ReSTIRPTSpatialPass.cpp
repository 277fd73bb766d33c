// ReSTIRPTSpatial: spatial path reuse of ReSTIR PT (Lin et al. 2022). See README.md.
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "passes/restir_pt/PathReservoir.h"

namespace loom {

class ReSTIRPTSpatialPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("reservoirs").doc("reservoirs to reuse between (after temporal reuse)");
        r.inputBuffer("primary").doc("this frame's primary hits (ReSTIRPTInitial)");
        r.outputBuffer("reservoirsOut")
            .bytesPerPixel(restir::kReservoirBytes, restir::kSettingsBytes)
            .doc("reservoirs after the last spatial round");
        // Ping-pong partner of reservoirsOut between rounds. Declared for every round count:
        // ports depending on `rounds` would recompile the graph (and reset its history) on
        // each change; with rounds = 1 it is unused and may alias other transients.
        r.scratchBuffer("pingPong")
            .bytesPerPixel(restir::kReservoirBytes, restir::kSettingsBytes)
            .doc("reservoirs of the rounds before the last (rounds > 1)");
        r.param("neighbours", 3).range(1, 8).doc("neighbours per round (at most 8)");
        r.param("radius", 20.0).min(1).doc("neighbour disk radius, pixels");
        r.param("rounds", 1).range(1, 8).doc("spatial reuse rounds, each reading the previous");
        r.param("normalThreshold", 0.5).range(-1, 1).doc("reject neighbours: normal cosine below");
        r.param("depthThreshold", 0.1).min(0).doc("reject neighbours: relative depth above");
        r.paramEnum("mis", "defensivePairwise", {"defensivePairwise", "pairwise", "balance"})
            .doc(
                "resampling MIS: defensive pairwise (default), pairwise, or the generalized "
                "balance heuristic over all techniques (k^2 + k shifts, copy shift only)");
        r.paramEnum("dofShift", "both", shaderEnum("DOF_SHIFT"))
            .doc(
                "Area ReSTIR with a thin lens: lens-vertex copy, primary-hit reconnection, or "
                "both combined by MIS (Zhang et al. 2024, Sec. 6)");
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/restir_pt/spatial.comp");
    }
    void execute(ExecuteContext& ctx) override {
        auto counters = mCounters.reset(ctx.gpu(), ctx.cmd());
        restir::dispatchSpatialRounds(*this, *mPipeline, ctx, param<int>("rounds"),
                                      ctx.buffer("reservoirs"), ctx.buffer("reservoirsOut"),
                                      ctx.scratchBuffer("pingPong"),
                                      [&](gpu::Bindings& b, const std::shared_ptr<gpu::Buffer>& src,
                                          const std::shared_ptr<gpu::Buffer>& dst) {
                                          b.set("ReservoirsIn", src)
                                              .set("ReservoirsOut", dst)
                                              .set("PrimaryIn", ctx.buffer("primary"))
                                              .set("RestirCounters", counters);
                                      });
    }
    void frameCompleted(gpu::Context& gpu) override { mCounters.read(gpu); }
    std::map<std::string, double> stats() const override { return mCounters.stats(); }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
    restir::ShiftCounters mCounters;
};

LOOM_REGISTER_PASS(ReSTIRPTSpatialPass, "ReSTIRPTSpatial",
                   "ReSTIR PT spatial reuse: shift neighbours' paths, defensive pairwise MIS");

}  // namespace loom
