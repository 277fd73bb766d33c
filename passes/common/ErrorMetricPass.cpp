// ErrorMetric: MSE, relMSE, RMSE or MAPE of an image against a reference, a per-pixel error
// image and its false-colour view. The scalar is read back after the frame (stats()).
#include <cmath>

#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/image/Image.h"
#include "core/util/Log.h"

namespace loom {

class ErrorMetricPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputTexture("image", gpu::Format::RGBA32F).doc("estimate");
        r.inputTexture("reference", gpu::Format::RGBA32F).doc("reference (same size)");
        r.outputTexture("error", gpu::Format::RGBA32F).doc("false-colour per-pixel error");
        r.outputTexture("perPixel", gpu::Format::R32F).doc("per-pixel error value");
        r.outputBuffer("value").bytes(16).doc("float: the metric over the whole image");
        r.paramEnum("metric", "relmse", {"mse", "relmse", "rmse", "mape"})
            .doc("relmse = mean((x-r)^2/(r^2+epsilon)); mape = mean(|x-r|/(|r|+epsilon))");
        r.param("epsilon", 1e-2).min(0).doc("stabiliser of relative metrics");
        r.param("falseColorMax", 1.0).min(1e-12).doc("error mapped to the top of the ramp");
        r.param("logScale", true).doc("logarithmic false-colour ramp");
    }
    void compile(ShaderLibrary& shaders) override {
        mPixel = compileKernel(*this, shaders, "passes/common/error_metric.comp");
        mReduce = compileKernel(*this, shaders, "passes/common/reduce.comp");
    }
    void execute(ExecuteContext& ctx) override {
        auto img = ctx.texture("image"), ref = ctx.texture("reference");
        if (img->width() != ref->width() || img->height() != ref->height())
            throw UserError(fmt::format("image is {}x{} but reference is {}x{}", img->width(),
                                        img->height(), ref->width(), ref->height()));
        // The per-pixel image and the reduction cover the frame: another size would read
        // outside the inputs and average in pixels that do not exist.
        if (img->width() != ctx.width() || img->height() != ctx.height())
            throw UserError(fmt::format("image and reference are {}x{} but the frame is {}x{}; "
                                        "render at the images' size",
                                        img->width(), img->height(), ctx.width(), ctx.height()));
        Metric m = parseMetric(param<std::string>("metric"));
        gpu::Bindings b;
        b.set("inputImage", img)
            .set("referenceImage", ref)
            .set("perPixelImage", ctx.texture("perPixel"))
            .set("errorImage", ctx.texture("error"));
        KernelParams(*this, *mPixel, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
        ctx.cmd().barrier();
        gpu::Bindings rb;
        mValue = ctx.buffer("value");
        rb.set("perPixelImage", ctx.texture("perPixel")).set("Result", mValue);
        KernelParams(*this, *mReduce, ctx).dispatchGroups(ctx, rb, 1);
        mMetric = m;
    }
    void frameCompleted(gpu::Context& gpu) override {
        float v = 0.0f;
        gpu.downloadBuffer(*mValue, &v, sizeof(float));
        mResult = mMetric == Metric::RMSE ? std::sqrt(double(v)) : double(v);
    }
    std::map<std::string, double> stats() const override {
        return {{metricName(mMetric), mResult}};
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPixel, mReduce;
    std::shared_ptr<gpu::Buffer> mValue;
    Metric mMetric = Metric::RelMSE;
    double mResult = 0.0;
};

LOOM_REGISTER_PASS(ErrorMetricPass, "ErrorMetric",
                   "MSE/relMSE/RMSE/MAPE against a reference, with a false-colour error image");

}  // namespace loom
