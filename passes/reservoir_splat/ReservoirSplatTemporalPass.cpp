// ReservoirSplatTemporal: temporal reuse of Area ReSTIR's path reservoirs by gathering
// (ReSTIRPTTemporal's kernel) or by reservoir splatting (Liu et al. 2025). See README.md.
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "passes/restir_pt/PathReservoir.h"

namespace loom {

namespace {

// SplatCounters (splat_buffers.glsl), in order.
enum SplatCounter : size_t {
    kSources,
    kLanded,
    kOccluded,
    kOffScreen,
    kAllocated,
    kResampled,
    kPixelsReached,
    kMaxPerPixel,
    kReverseAttempts,
    kReverseSuccess,
    kDropped,
    kPixels,
    kNotArea,
    kBackupAttempts,
    kBackupSuccess,
    kSplatCounters
};
constexpr uint64_t kSplatRecordBytes = 32;
constexpr int kMaxTimePartitions = 4;  // MAX_TIME_PARTITIONS, splat_buffers.glsl

}  // namespace

class ReservoirSplatTemporalPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        restir::reflectTemporalReuse(r);
        r.paramEnum("mode", "scatter", {"gather", "scatter", "scatter_backup", "multi_scatter"})
            .doc(
                "gather: Area ReSTIR's backprojection (ReSTIRPTTemporal, areaReprojection fast or "
                "robust); scatter: every previous sample is forward-projected with its primary hit "
                "kept and resampled where it lands (Liu et al. 2025); scatter_backup: also the "
                "previous pixel at the rounded motion vector by lens-vertex copy, 3-term MIS; "
                "multi_scatter: motion blur, every previous sample splatted once per time "
                "partition (Sec. 4.4; needs ReSTIRPTInitial.motionBlur)");
        r.param("timePartitions", 2)
            .range(1, kMaxTimePartitions)
            .doc(
                "multi_scatter: K, the shutter split into K partitions, each receiving the whole "
                "previous shutter squeezed by 1/K");
        r.paramEnum("ablation", "none",
                    {"none", "sumSplatConfidences", "noReverseSplat", "noTimeJacobian"})
            .doc(
                "scatter, biased on purpose for the tests: sum the landed splats' confidences "
                "instead of Eq. 17's bilinear one, drop the canonical sample's reverse-splat MIS "
                "term, or drop multi_scatter's 1/K time Jacobian");
        r.scratchBuffer("records")
            .bytesPerPixel(kSplatRecordBytes * kMaxTimePartitions)
            .doc(
                "scatter: per previous pixel, where its sample landed (pixel, offset, x1, "
                "Jacobian)");
        r.scratchBuffer("ranges").bytesPerPixel(8).doc(
            "scatter: per pixel, splats landed and the start of its index-list range");
        r.scratchBuffer("lists")
            .bytesPerPixel(4 * kMaxTimePartitions)
            .doc("scatter: source pixels of the splats, grouped by destination");
    }
    void compile(ShaderLibrary& shaders) override {
        mGather = compileKernel(*this, shaders, "passes/restir_pt/temporal.comp");
        mForward = compileKernel(*this, shaders, "passes/reservoir_splat/splat_forward.comp");
        mAllocate = compileKernel(*this, shaders, "passes/reservoir_splat/splat_allocate.comp");
        mList = compileKernel(*this, shaders, "passes/reservoir_splat/splat_list.comp");
        mResample = compileKernel(*this, shaders, "passes/reservoir_splat/splat_resample.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::Bindings b = restir::temporalReuseBindings(ctx, mShiftCounters);
        mScatter = param<std::string>("mode") != "gather";
        if (!mScatter) {
            KernelParams(*this, *mGather, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
            return;
        }
        auto ranges = ctx.scratchBuffer("ranges");
        ctx.cmd().fillBuffer(*ranges, 0u);
        b.set("SplatRecords", ctx.scratchBuffer("records"))
            .set("SplatRanges", ranges)
            .set("SplatLists", ctx.scratchBuffer("lists"))
            .set("SplatCounters", mSplatCounters.reset(ctx.gpu(), ctx.cmd()));
        const gpu::ComputePipeline* steps[] = {mForward.get(), mAllocate.get(), mList.get(),
                                               mResample.get()};
        for (const gpu::ComputePipeline* k : steps) {
            KernelParams(*this, *k, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
            ctx.cmd().barrier();
        }
    }
    void frameCompleted(gpu::Context& gpu) override {
        mShiftCounters.read(gpu);
        if (mScatter) mSplatCounters.read(gpu);
    }
    std::map<std::string, double> stats() const override {
        auto s = mShiftCounters.stats();
        if (!mScatter) return s;
        const auto& c = mSplatCounters;
        double pixels = std::max(1.0, double(c[kPixels]));
        s["splatSources"] = c[kSources];
        s["splatLanded"] = c[kLanded];
        s["splatOccluded"] = c[kOccluded];
        s["splatOffScreen"] = c[kOffScreen];
        s["splatAllocated"] = c[kAllocated];
        s["splatResampled"] = c[kResampled];
        s["splatDropped"] = c[kDropped];
        s["splatsPerPixelMean"] = c[kLanded] / pixels;
        s["splatsPerPixelMax"] = c[kMaxPerPixel];
        s["splatUnreachedShare"] = c[kPixels] > 0 ? 1.0 - c[kPixelsReached] / pixels : 0.0;
        s["reverseSplatAttempts"] = c[kReverseAttempts];
        s["reverseSplatSuccess"] = c[kReverseSuccess];
        s["notAreaPixels"] = c[kNotArea];
        s["backupAttempts"] = c[kBackupAttempts];
        s["backupSuccess"] = c[kBackupSuccess];
        return s;
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mGather, mForward, mAllocate, mList, mResample;
    restir::ShiftCounters mShiftCounters;
    gpu::CounterBuffer<kSplatCounters> mSplatCounters{"SplatCounters"};
    bool mScatter = false;
};

LOOM_REGISTER_PASS(ReservoirSplatTemporalPass, "ReservoirSplatTemporal",
                   "temporal path reuse by reservoir splatting (Liu et al. 2025) or Area "
                   "ReSTIR's gather");

}  // namespace loom
