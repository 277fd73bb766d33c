// PartitionedSMS: unbiased caustics by sample-space-partitioned specular manifold sampling
// with a per-frame prior (Hong et al. 2025 Sec. 4), 1 sample per pixel, at the primary
// receivers of a path tracer that leaves out the paths it produces. See README.md.
#include <fmt/format.h>

#include <algorithm>

#include "core/gpu/CounterBuffer.h"
#include "core/gpu/WorkList.h"
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "core/util/Log.h"
#include "passes/partitioned_sms/ManifoldPairs.h"
#include "passes/partitioned_sms/ManifoldReuse.h"
#include "passes/sms/ManifoldParams.h"

namespace loom {

namespace {

constexpr uint64_t kPixelBytes = 192;  // PsmsPixel (psms_common.glsl)

enum Counter { kSamples, kSolved, kIterations, kWalks, kBernoulli, kCapped, kMaxSteps, kRays };

}  // namespace

class PartitionedSMSPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("prior").optional().doc("ManifoldPrior.prior (needed when prior is on)");
        r.outputTexture("color", gpu::Format::RGBA32F)
            .doc("full image: path tracer without the SMS-covered paths + caustic");
        r.outputTexture("caustic", gpu::Format::RGBA32F)
            .optional()
            .doc("the caustic estimate alone (primary receivers)");
        r.outputTexture("stats", gpu::Format::RGBA32F)
            .optional()
            .doc("per pixel: Newton iterations, solution found, walks, estimate taken");
        r.outputTexture("path", gpu::Format::RGBA32F)
            .optional()
            .doc("the path tracer's part alone (to add reused caustics to)");
        r.outputBuffer("reservoirs")
            .optional()
            .bytesPerPixel(kManifoldReservoirBytes, kManifoldReservoirHeaderBytes)
            .doc("the caustic samples as reservoirs, for ManifoldReSTIRTemporal/Spatial");
        r.scratchTexture("pathPart").doc("the path tracer's part (when path is not connected)");
        r.scratchBuffer("pixels").bytesPerPixel(kPixelBytes).doc("estimator state per pixel");
        r.scratchBuffer("active").bytesPerPixel(8).doc(
            "two lists of the pixels whose estimate still runs (lib/work_list.glsl)");
        r.param("tiles", 16)
            .range(1, 32)
            .doc("N: the seed space is cut into N x N tiles, a divisor of 32 (1: plain SMS)");
        r.param("prior", true)
            .doc("sample pairs and seeds from ManifoldPrior's tile sets (off: partitioning alone)");
        r.param("alpha", 0.8)
            .range(0.0, 0.99)
            .doc("weight of the prior in the pair choice and the seed mixture (Eq. 7)");
        reflectManifoldWalk(r);
        r.param("maxTrials", 128).min(1).doc("Bernoulli trials before the cap (paper: 128)");
        r.paramEnum("trialCap", "keep", {"drop", "keep"})
            .doc("at the cap: keep the sample with K = maxTrials (paper) or drop it (SMS code)");
        r.param("roughCasters", true)
            .doc(
                "rough conductor and dielectric casters scatter about offset normals, one set "
                "per estimate, kept by its trials and replayed by the manifold shift (off: "
                "their caustics stay with the path tracer)");
        reflectCausticPath(r, 16);
    }
    void execute(ExecuteContext& ctx) override {
        const auto& scene = ctx.scene();
        int tiles = param<int>("tiles");
        if (32 % tiles != 0)
            throw UserError(
                fmt::format("pass '{}': tiles = {} does not divide 32 (1, 2, 4, 8, "
                            "16 or 32)",
                            name(), tiles));
        bool prior = param<bool>("prior");
        if (prior && !ctx.has("prior"))
            throw UserError(fmt::format(
                "pass '{}': prior is on but no ManifoldPrior is connected to its 'prior' input "
                "(connect one, or set prior = false)",
                name()));
        mPairs.build(ctx, name());
        ShaderDefines defines{{"HAS_STATS", ctx.has("stats") ? "1" : "0"},
                              {"HAS_CAUSTIC", ctx.has("caustic") ? "1" : "0"},
                              {"HAS_RESERVOIRS", ctx.has("reservoirs") ? "1" : "0"}};
        ShaderDefines chain{{"MANIFOLD_MAX_VERTICES", std::to_string(param<int>("maxChain"))}};
        // Compiled in only where the scene has rough casters (llvmpipe runs untaken branches
        // masked).
        if (param<bool>("roughCasters") && ManifoldPairs::roughCasters(scene.cpu()))
            chain.insert_or_assign("MANIFOLD_ROUGH_CASTERS", std::string("1"));
        auto kernel = [&](const char* file, const ShaderDefines& d) {
            return compileKernel(*this, ctx.shaders(),
                                 std::string("passes/partitioned_sms/") + file, d);
        };
        auto path = kernel("psms_path.comp", chain);
        auto trials = kernel("psms_trials.comp", chain);
        auto resolve = kernel("psms_resolve.comp", defines);
        auto counters = mCounters.reset(ctx.gpu(), ctx.cmd());
        mWork.reset(ctx.gpu(), ctx.cmd());
        if (!mNoPrior) mNoPrior = ctx.gpu().createBuffer(16, "ManifoldPrior (none)");
        float minSegment = 1e-4f * std::max(scene.boundingSphere().w, 1e-6f);

        gpu::Bindings b;
        scene.bind(b);
        mPairs.bind(b);
        b.set("ManifoldPrior", ctx.has("prior") ? ctx.buffer("prior") : mNoPrior)
            .set("PsmsPixels", ctx.scratchBuffer("pixels"))
            .set("PsmsCounters", counters)
            .set("pathImage",
                 ctx.has("path") ? ctx.texture("path") : ctx.scratchTexture("pathPart"))
            .set("colorImage", ctx.texture("color"));
        if (ctx.has("caustic")) b.set("causticImage", ctx.texture("caustic"));
        if (ctx.has("stats")) b.set("statsImage", ctx.texture("stats"));
        if (ctx.has("reservoirs")) b.set("ReservoirsOut", ctx.buffer("reservoirs"));
        mWork.bind(b, ctx.scratchBuffer("active"));
        auto params = [&](gpu::ComputePipeline& p) {
            KernelParams k(*this, p, ctx);
            k.set("minSegment", minSegment);
            k.set("dispatchIndex", 0u);
            k.set("prior", uint32_t(prior && ctx.has("prior")));
            return k;
        };
        params(*path).dispatch(ctx, b, ctx.width(), ctx.height());
        for (int i = 0; i < param<int>("trialDispatches"); ++i) {
            ctx.cmd().barrier();
            params(*trials)
                .set("dispatchIndex", uint32_t(i))
                .dispatchIndirect(ctx, b, mWork.args(), gpu::WorkList::argsOffset(i));
        }
        ctx.cmd().barrier();
        params(*resolve).dispatch(ctx, b, ctx.width(), ctx.height());
    }
    void frameCompleted(gpu::Context& gpu) override {
        mCounters.read(gpu);
        for (int i = 0; i < 8; ++i) mTotals[i] += mCounters[i];
        if (mCounters[kMaxSteps] >= 65535u - 16u && !mWarnedLoopLimit) {
            logWarning(
                "PartitionedSMS: an invocation ran {} BVH steps in one dispatch, at lavapipe's "
                "loop limit (65535): lower stepBudget",
                mCounters[kMaxSteps]);
            mWarnedLoopLimit = true;
        }
    }
    void onParamChanged(const std::string&) override { std::fill(mTotals, mTotals + 8, 0.0); }
    // Hong et al. 2025 Table 1 columns over the frames rendered so far.
    std::map<std::string, double> stats() const override {
        auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
        const double* t = mTotals;
        return {{"samples", t[kSamples]},
                {"solutions", t[kSolved]},
                {"successRate", ratio(t[kSolved], t[kSamples])},
                {"iterationsPerSample", ratio(t[kIterations], t[kSamples])},
                {"trialsPerSolution", ratio(t[kBernoulli], t[kSolved])},
                {"iterationsPerSolution", ratio(t[kIterations], t[kSolved])},
                {"walks", t[kWalks]},
                {"capped", t[kCapped]},
                {"rays", t[kRays]},
                {"maxTraversalSteps", double(mCounters[kMaxSteps])}};
    }

private:
    ManifoldPairs mPairs;
    std::shared_ptr<gpu::Buffer> mNoPrior;
    gpu::WorkList mWork;
    gpu::CounterBuffer<8> mCounters{"PsmsCounters"};
    double mTotals[8] = {};
    bool mWarnedLoopLimit = false;
};

LOOM_REGISTER_PASS(PartitionedSMSPass, "PartitionedSMS",
                   "Unbiased caustics by sample-space-partitioned SMS with a per-frame prior "
                   "(Hong et al. 2025), with a path tracer that leaves out the paths it produces");

}  // namespace loom
