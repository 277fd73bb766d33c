// ManifoldPrior: the per-frame prior of sample-space-partitioned SMS (Hong et al. 2025 Sec.
// 4.2). Per 16 x 16 pixel block, presample threads run unrestricted manifold walks and OR the
// seed-space tiles of the solutions they find into per light-caster pair tile sets, which
// PartitionedSMS samples seeds and pairs from. See README.md.
#include <algorithm>

#include "core/gpu/CounterBuffer.h"
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "core/util/Log.h"
#include "passes/partitioned_sms/ManifoldPairs.h"

namespace loom {

namespace {

// Mirrored from shaders/lib/manifold/prior.glsl: blocks of 16 x 16 pixels, 8 pair slots of
// 33 words each. A fixed size (per-block records have no per-pixel stride): frames up to
// 2048 x 2048 pixels, 17.3 MB.
constexpr uint64_t kBlock = 16, kSlotBytes = 33 * 4, kSlots = 8;
constexpr uint64_t kBlockBytes = kSlots * kSlotBytes;
constexpr uint64_t kMaxFrame = 2048;
constexpr uint64_t kPriorBytes = (kMaxFrame / kBlock) * (kMaxFrame / kBlock) * kBlockBytes;

enum PriorCounter {
    kPriorWalks,
    kPriorSolutions,
    kPriorOverflow,
    kPriorIterations,
    kPriorMaxSteps
};

}  // namespace

class ManifoldPriorPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.outputBuffer("prior")
            .bytes(kPriorBytes)
            .doc(
                "per 16 x 16 block, up to 8 light-caster pairs with the 32 x 32 seed-space tiles "
                "their solutions fell in (lib/manifold/prior.glsl)");
        r.outputTexture("tileMap", gpu::Format::RGBA32F)
            .optional()
            .doc("debug: the tile set of pair slot debugSlot of the block holding debugPixel");
        r.param("presamples", 128)
            .range(64, 4096)
            .doc("presample threads per block (paper: 128, 256 for hard cases); multiple of 64");
        r.paramEnum("constraint", "angle_difference", shaderEnum("MANIFOLD_CONSTRAINT"))
            .doc("specular constraint of the presample walks");
        r.param("maxIterations", 20).range(1, 1000).doc("Newton steps per presample walk");
        r.param("solverThreshold", 1e-5).min(0).doc("convergence: every |C_i| below this");
        r.param("maxChain", 2).range(1, 4).doc("specular vertices of a chain");
        r.paramVec("debugPixel", {0.0, 0.0}).doc("tileMap: a pixel of the block shown");
        r.param("debugSlot", 0).range(0, int(kSlots) - 1).doc("tileMap: which listed pair");
    }
    void execute(ExecuteContext& ctx) override {
        const auto& scene = ctx.scene();
        mPairs.build(ctx, name());
        ShaderDefines chain{{"MANIFOLD_MAX_VERTICES", std::to_string(param<int>("maxChain"))}};
        // Rough casters: presample walks scatter about offset normals of their own.
        if (ManifoldPairs::roughCasters(ctx.scene().cpu()))
            chain.insert_or_assign("MANIFOLD_ROUGH_CASTERS", std::string("1"));
        auto prior =
            compileKernel(*this, ctx.shaders(), "passes/partitioned_sms/prior.comp", chain);
        auto buffer = ctx.buffer("prior");
        uint64_t blocksX = (ctx.width() + kBlock - 1) / kBlock;
        uint64_t blocks = blocksX * ((ctx.height() + kBlock - 1) / kBlock);
        if (blocks * kBlockBytes > buffer->size())
            throw UserError(fmt::format("pass '{}': frames up to {} x {} pixels, not {}x{}", name(),
                                        kMaxFrame, kMaxFrame, ctx.width(), ctx.height()));
        auto counters = mCounters.reset(ctx.gpu(), ctx.cmd());
        ctx.cmd().fillBuffer(*buffer, 0);
        ctx.cmd().barrier();
        gpu::Bindings b;
        scene.bind(b);
        mPairs.bind(b);
        b.set("ManifoldPrior", buffer).set("PriorCounters", counters);
        KernelParams k(*this, *prior, ctx);
        k.set("minSegment", 1e-4f * std::max(scene.boundingSphere().w, 1e-6f));
        uint32_t groups = uint32_t((param<int>("presamples") + 63) / 64);
        k.dispatchGroups(ctx, b, groups, uint32_t(blocks));
        if (ctx.has("tileMap")) {
            ctx.cmd().barrier();
            auto view =
                compileKernel(*this, ctx.shaders(), "passes/partitioned_sms/prior_view.comp");
            gpu::Bindings v;
            v.set("ManifoldPrior", buffer).set("tileImage", ctx.texture("tileMap"));
            KernelParams(*this, *view, ctx).dispatch(ctx, v, ctx.width(), ctx.height());
        }
    }
    void frameCompleted(gpu::Context& gpu) override {
        mCounters.read(gpu);
        for (int i = 0; i < 4; ++i) mTotals[i] += mCounters[i];
        if (mCounters[kPriorMaxSteps] >= 65535u - 16u && !mWarned) {
            logWarning("ManifoldPrior: a presample ran {} BVH steps, at lavapipe's loop limit",
                       mCounters[kPriorMaxSteps]);
            mWarned = true;
        }
    }
    void onParamChanged(const std::string&) override { std::fill(mTotals, mTotals + 4, 0.0); }
    std::map<std::string, double> stats() const override {
        return {{"walks", mTotals[kPriorWalks]},
                {"solutions", mTotals[kPriorSolutions]},
                {"overflow", mTotals[kPriorOverflow]},
                {"iterations", mTotals[kPriorIterations]},
                {"maxTraversalSteps", double(mCounters[kPriorMaxSteps])}};
    }

private:
    ManifoldPairs mPairs;
    gpu::CounterBuffer<5> mCounters{"PriorCounters"};
    double mTotals[4] = {};
    bool mWarned = false;
};

LOOM_REGISTER_PASS(ManifoldPriorPass, "ManifoldPrior",
                   "Per-frame seed-space prior of partitioned SMS: tiles of presampled manifold "
                   "solutions per pixel block and light-caster pair (Hong et al. 2025)");

}  // namespace loom
