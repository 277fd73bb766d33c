// Enumerations the ReSTIR PT library reads from its buffers (shaders/lib/restir): declared once
// here, they reach every kernel as SHIFT_* and DOF_SHIFT_* defines (ShaderEnums.h).
#include "passes/restir_pt/PathReservoir.h"

#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"

namespace loom::restir {

LOOM_REGISTER_SHADER_ENUM(Shift, "SHIFT", {"hybrid", "reconnection", "replay"},
                          "shift mapping of all reuse (Lin et al. 2022, Sec. 6)");
LOOM_REGISTER_SHADER_ENUM(
    DofShift, "DOF_SHIFT", {"both", "copy", "reconnect"},
    "Area ReSTIR primary-vertex shifts under a thin lens (Zhang et al. 2024)");

void reflectTemporalReuse(PassReflection& r) {
    r.inputBuffer("reservoirs").doc("this frame's reservoirs (ReSTIRPTInitial)");
    r.inputBuffer("primary").doc("this frame's primary hits (ReSTIRPTInitial)");
    r.inputBuffer("prevReservoirs")
        .previousFrame()
        .doc("last frame's final reservoirs: connect the last reuse stage's output");
    r.inputBuffer("prevPrimary")
        .previousFrame()
        .doc("last frame's primary hits: connect ReSTIRPTInitial.primary");
    r.inputTexture("motion", gpu::Format::RG32F).doc("GBuffer.motion (pixels)");
    r.outputBuffer("reservoirsOut")
        .bytesPerPixel(restir::kReservoirBytes, restir::kSettingsBytes)
        .doc("reservoirs after temporal reuse");
    r.param("confidenceCap", 20.0)
        .min(0)
        .doc("history length: previous confidence clamped to cap x current (Lin et al. Sec. 7)");
    r.param("normalThreshold", 0.5).range(-1, 1).doc("reject history: normal cosine below");
    r.param("depthThreshold", 0.1).min(0).doc("reject history: relative depth difference above");
    r.paramEnum("mis", "balance", {"balance", "uniform"})
        .doc(
            "generalized balance heuristic (Talbot), or confidence weights over techniques "
            "that "
            "can shift the sample (1/|Z|)");
    r.paramEnum("areaReprojection", "fast", {"fast", "robust", "copy"})
        .doc(
            "Area ReSTIR only (initial.reuse = area): fractional motion vectors over the 2x2 "
            "previous pixels, resampled by previous targets then shifted (fast) or all "
            "shifted first (robust); copy = one previous pixel, subpixel offset copied");
    r.paramEnum("dofShift", "both", shaderEnum("DOF_SHIFT"))
        .doc(
            "Area ReSTIR with a thin lens: lens-vertex copy, primary-hit reconnection, or "
            "both combined by MIS (Zhang et al. 2024, Sec. 6; needs mis = balance)");
    r.paramEnum("movingSuffix", "reject", {"reject", "reuse"})
        .doc(
            "paths with a cached suffix after the reconnection vertex when shapes moved since "
            "the previous frame: reject (the temporal shift fails: exact) or reuse the "
            "suffix's radiance unchecked (biased near moving shapes)");
    r.param("countFailedShifts", false)
        .doc(
            "ablation, biased: with mis=uniform, count the history even when the current "
            "sample "
            "cannot shift to it (the known darkening bug)");
}

gpu::Bindings temporalReuseBindings(ExecuteContext& ctx, ShiftCounters& counters) {
    gpu::Bindings b;
    ctx.scene().bind(b);
    b.set("ReservoirsIn", ctx.buffer("reservoirs"))
        .set("PrevReservoirs", ctx.buffer("prevReservoirs"))
        .set("PrimaryIn", ctx.buffer("primary"))
        .set("PrevPrimary", ctx.buffer("prevPrimary"))
        .set("motionImage", ctx.texture("motion"))
        .set("ReservoirsOut", ctx.buffer("reservoirsOut"))
        .set("RestirCounters", counters.reset(ctx.gpu(), ctx.cmd()));
    return b;
}

void dispatchSpatialRounds(
    const Pass& pass, const gpu::ComputePipeline& pipeline, ExecuteContext& ctx, int rounds,
    std::shared_ptr<gpu::Buffer> in, const std::shared_ptr<gpu::Buffer>& out,
    const std::shared_ptr<gpu::Buffer>& pingPong,
    const std::function<void(gpu::Bindings&, const std::shared_ptr<gpu::Buffer>& src,
                             const std::shared_ptr<gpu::Buffer>& dst)>& bind) {
    for (int round = 0; round < rounds; ++round) {
        auto dst = (rounds - 1 - round) % 2 == 0 ? out : pingPong;
        gpu::Bindings b;
        ctx.scene().bind(b);
        bind(b, in, dst);
        KernelParams(pass, pipeline, ctx)
            .set("round", uint32_t(round))
            .dispatch(ctx, b, ctx.width(), ctx.height());
        ctx.cmd().barrier();
        in = dst;
    }
}

}  // namespace loom::restir
