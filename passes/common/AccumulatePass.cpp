// Accumulate: running mean and per-pixel variance over frames; resets when anything upstream
// changes (parameters, graph, size, camera). See README.md.
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"

namespace loom {

class AccumulatePass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputTexture("input", gpu::Format::RGBA32F).doc("per-frame estimate");
        r.outputTexture("output", gpu::Format::RGBA32F).doc("mean over accumulated frames");
        r.outputTexture("variance", gpu::Format::RGBA32F)
            .optional()
            .doc("rgb: unbiased per-pixel sample variance of the frames; a: frame count");
        r.param("enabled", true).doc("accumulate; when false the input passes through");
        r.param("maxFrames", 0).min(0).doc("stop after this many frames (0 = never)");
        r.persistentTexture("mean", gpu::Format::RGBA32F, "running mean");
        r.persistentTexture("m2", gpu::Format::RGBA32F, "running sum of squared deviations");
    }
    void compile(ShaderLibrary& shaders) override {
        const char* kernel = "passes/common/accumulate.comp";
        mPipeline = compileKernel(*this, shaders, kernel, {{"HAS_VARIANCE", "0"}});
        mPipelineVar = compileKernel(*this, shaders, kernel, {{"HAS_VARIANCE", "1"}});
    }
    void execute(ExecuteContext& ctx) override {
        if (ctx.upstreamChanged() || ctx.historyReset()) mCount = 0;
        bool enabled = param<bool>("enabled");
        int maxFrames = param<int>("maxFrames");
        if (!enabled) mCount = 0;
        bool frozen = enabled && maxFrames > 0 && mCount >= uint32_t(maxFrames);
        auto variance = ctx.texture("variance");
        const auto& pipeline = variance ? *mPipelineVar : *mPipeline;
        gpu::Bindings b;
        b.set("inputImage", ctx.texture("input"))
            .set("meanImage", ctx.persistentTexture("mean"))
            .set("m2Image", ctx.persistentTexture("m2"))
            .set("outputImage", ctx.texture("output"));
        if (variance) b.set("varianceImage", variance);
        // Frozen (maxFrames reached): the kernel reports the converged mean and variance.
        KernelParams(*this, pipeline, ctx)
            .set("count", mCount)
            .set("frozen", uint32_t(frozen))
            .dispatch(ctx, b, ctx.width(), ctx.height());
        if (enabled && !frozen) ++mCount;
    }
    std::map<std::string, double> stats() const override { return {{"frames", double(mCount)}}; }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline, mPipelineVar;
    uint32_t mCount = 0;
};

LOOM_REGISTER_PASS(AccumulatePass, "Accumulate",
                   "Running mean and per-pixel variance over frames; resets on upstream change");

}  // namespace loom
