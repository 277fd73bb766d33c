// Shared host side of ManifoldReSTIRTemporal and ManifoldReSTIRSpatial. See ManifoldReuse.h.
#include "passes/partitioned_sms/ManifoldReuse.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "core/util/Log.h"
#include "passes/partitioned_sms/ManifoldPairs.h"

namespace loom {

void reflectManifoldReuse(PassReflection& r) {
    r.outputBuffer("reservoirsOut")
        .bytesPerPixel(kManifoldReservoirBytes, kManifoldReservoirHeaderBytes)
        .doc("reservoirs after this reuse");
    r.outputTexture("caustic", gpu::Format::RGBA32F)
        .optional()
        .doc("the caustic the reservoirs estimate, F W");
    r.inputTexture("path").optional().doc(
        "the path tracer's part (PartitionedSMS.path), for the full image");
    r.outputTexture("color", gpu::Format::RGBA32F)
        .optional()
        .doc("full image: path + caustic (needs path)");
    r.paramEnum("constraint", "angle_difference", shaderEnum("MANIFOLD_CONSTRAINT"))
        .doc("specular constraint of the shift's walk (PartitionedSMS's)");
    r.param("shiftIterations", 5)
        .range(1, 1000)
        .doc("Newton steps of a shift's walk, seeded at the source solution (paper: 5)");
    r.param("solverThreshold", 1e-5).min(0).doc("convergence: every |C_i| below this");
    r.param("uniquenessThreshold", 1e-5)
        .min(0)
        .doc("the walk back found the source solution: first directions |d.d' - 1| below this");
    r.param("bijectivity", true)
        .doc(
            "walk back after each shift and fail it unless it returns to the source (off: "
            "an ablation, biased where shifts are not invertible)");
    r.param("geometricTermClamp", 0.0)
        .min(0)
        .doc("clamp of the generalized geometric term (0 = off; biased)");
    r.param("maxChain", 2).range(1, 4).doc("specular vertices of a chain (PartitionedSMS's)");
}

gpu::ComputePipeline& ManifoldReusePass::kernel(ExecuteContext& ctx, const std::string& file) {
    ShaderDefines d{{"HAS_CAUSTIC", ctx.has("caustic") ? "1" : "0"},
                    {"HAS_PATH", ctx.has("color") ? "1" : "0"},
                    {"MANIFOLD_MAX_VERTICES", std::to_string(param<int>("maxChain"))}};
    // Samples through rough casters carry their offset normals' stream; the shift replays it.
    if (ManifoldPairs::roughCasters(ctx.scene().cpu()))
        d.insert_or_assign("MANIFOLD_ROUGH_CASTERS", std::string("1"));
    std::string key;
    for (const auto& [k, v] : d) key += k + "=" + v + ";";
    auto& k = mKernels[key];
    if (!k) k = compileKernel(*this, ctx.shaders(), "passes/partitioned_sms/" + file, d);
    return *k;
}

gpu::Bindings ManifoldReusePass::bindings(ExecuteContext& ctx, const std::string& input) {
    if (ctx.has("color") && !ctx.has("path"))
        throw UserError(fmt::format(
            "pass '{}': output 'color' needs the path tracer's part on input 'path' (connect "
            "PartitionedSMS.path)",
            name()));
    gpu::Bindings b;
    ctx.scene().bind(b);
    b.set("ReservoirsIn", ctx.buffer(input))
        .set("ReservoirsOut", ctx.buffer("reservoirsOut"))
        .set("ManifoldReuseCounters", mCounters.reset(ctx.gpu(), ctx.cmd()));
    if (ctx.has("caustic")) b.set("causticImage", ctx.texture("caustic"));
    if (ctx.has("color"))
        b.set("pathImage", ctx.texture("path")).set("colorImage", ctx.texture("color"));
    return b;
}

KernelParams ManifoldReusePass::params(ExecuteContext& ctx, gpu::ComputePipeline& k) const {
    KernelParams p(*this, k, ctx);
    p.set("minSegment", 1e-4f * std::max(ctx.scene().boundingSphere().w, 1e-6f));
    return p;
}

void ManifoldReusePass::frameCompleted(gpu::Context& gpu) {
    mCounters.read(gpu);
    if (mCounters[4] >= 65535u - 16u && !mWarnedLoopLimit) {
        logWarning("{}: an invocation ran {} BVH steps, at lavapipe's loop limit (65535)", name(),
                   mCounters[4]);
        mWarnedLoopLimit = true;
    }
}

std::map<std::string, double> ManifoldReusePass::stats() const {
    double attempts = mCounters[0];
    return {{"shiftAttempts", attempts},
            {"shiftSuccess", double(mCounters[1])},
            {"shiftSuccessRate", attempts > 0 ? mCounters[1] / attempts : 0.0},
            {"walkBackFailures", double(mCounters[2])},
            {"rays", double(mCounters[3])},
            {"maxTraversalSteps", double(mCounters[4])}};
}

}  // namespace loom
