// Gradient-domain ReSTIR PT (Wang et al. 2025) as four passes over paired-pixel reservoirs:
// PairedPixelInitial, PairedPixelTemporal, PairedPixelSpatial and PairedPixelResolve
// (paired_pixel.glsl holds the shared definitions). See README.md, "ReSTIR G-PT".
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "passes/gradient_domain/GradientImages.h"
#include "passes/restir_pt/PathReservoir.h"

namespace loom {

namespace {
constexpr uint64_t kPairSettingsBytes = 48;    // PairSettings
constexpr uint64_t kPairSlotsBytes = 4 * 112;  // PairSlots: 4 PairReservoir
constexpr uint64_t kPixelFeaturesBytes = 32;   // PixelFeatures

// The G-buffer tests both reuse passes apply to pixels of pairs (paired_pixel.glsl).
void reflectPixelTests(PassReflection& r) {
    r.param("normalThreshold", 0.9)
        .range(-1, 1)
        .doc("pixels alike: normal cosine at least this (the paper's 0.9)");
    r.param("depthThreshold", 0.1).min(0).doc("pixels alike: relative depth difference at most");
    r.param("albedoThreshold", 0.1)
        .min(0)
        .doc("pixels alike: reflectance difference (max channel) at most");
}
}  // namespace

class PairedPixelInitialPass : public restir::ShiftCountingPass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("reservoirs")
            .doc("the pixels' initial path candidates (ReSTIRPTInitial.reservoirs, reuse = area)");
        r.inputBuffer("primary").doc("ReSTIRPTInitial.primary");
        r.outputBuffer("pairs")
            .bytesPerPixel(kPairSlotsBytes, kPairSettingsBytes)
            .doc("paired-pixel reservoirs: per pixel the +x and +y pairs, a reservoir per sign");
        r.outputBuffer("features")
            .bytesPerPixel(kPixelFeaturesBytes)
            .doc("the pixels' normal, depth and albedo for the reuse passes' tests");
        r.param("positivization", true)
            .doc(
                "separate reservoirs for the pair integrand's positive and negative parts, never "
                "reused across (Sec. 5.2, Fig. 9); off: one reservoir with target |g|");
        r.paramEnum("measure", "mixed", {"mixed", "solidAngle"})
            .doc(
                "measure of the pair integrand: mixed (area at the reconnection vertex; the "
                "hybrid shift's Jacobian is 1) or solid angle at its predecessor (the paper's; "
                "shifts carry the reconnection Jacobian). The estimates agree");
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/gradient_domain/paired_initial.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::Bindings b;
        ctx.scene().bind(b);
        b.set("ReservoirsIn", ctx.buffer("reservoirs"))
            .set("PrimaryIn", ctx.buffer("primary"))
            .set("PairsOut", ctx.buffer("pairs"))
            .set("FeaturesOut", ctx.buffer("features"))
            .set("RestirCounters", mCounters.reset(ctx.gpu(), ctx.cmd()));
        KernelParams(*this, *mPipeline, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
};

class PairedPixelTemporalPass : public restir::ShiftCountingPass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("pairs").doc("this frame's pair reservoirs (PairedPixelInitial.pairs)");
        r.inputBuffer("primary").doc("this frame's primary hits (ReSTIRPTInitial.primary)");
        r.inputBuffer("prevPairs")
            .previousFrame()
            .doc("last frame's final pair reservoirs: connect the last pair stage's output");
        r.inputBuffer("prevPrimary")
            .previousFrame()
            .doc("last frame's primary hits: connect ReSTIRPTInitial.primary");
        r.inputBuffer("features")
            .doc("the pixels' G-buffer features (PairedPixelInitial.features)");
        r.inputBuffer("prevFeatures")
            .previousFrame()
            .doc("last frame's features: connect PairedPixelInitial.features");
        r.inputTexture("motion", gpu::Format::RG32F).doc("GBuffer.motion (pixels)");
        r.outputBuffer("pairsOut")
            .bytesPerPixel(kPairSlotsBytes, kPairSettingsBytes)
            .doc("pair reservoirs after temporal reuse");
        r.param("confidenceCap", 20.0)
            .min(0)
            .doc("history length: previous confidence clamped to cap x current");
        reflectPixelTests(r);
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/gradient_domain/paired_temporal.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::Bindings b;
        ctx.scene().bind(b);
        b.set("PairsIn", ctx.buffer("pairs"))
            .set("PrevPairs", ctx.buffer("prevPairs"))
            .set("PairsOut", ctx.buffer("pairsOut"))
            .set("PrimaryIn", ctx.buffer("primary"))
            .set("PrevPrimary", ctx.buffer("prevPrimary"))
            .set("FeaturesIn", ctx.buffer("features"))
            .set("PrevFeatures", ctx.buffer("prevFeatures"))
            .set("motionImage", ctx.texture("motion"))
            .set("RestirCounters", mCounters.reset(ctx.gpu(), ctx.cmd()));
        KernelParams(*this, *mPipeline, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
};

class PairedPixelSpatialPass : public restir::ShiftCountingPass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("pairs").doc("pair reservoirs to reuse between (after temporal reuse)");
        r.inputBuffer("primary").doc("this frame's primary hits (ReSTIRPTInitial.primary)");
        r.inputBuffer("features")
            .doc("the pixels' G-buffer features (PairedPixelInitial.features)");
        r.outputBuffer("pairsOut")
            .bytesPerPixel(kPairSlotsBytes, kPairSettingsBytes)
            .doc("pair reservoirs after the last round");
        r.scratchBuffer("pingPong")
            .bytesPerPixel(kPairSlotsBytes, kPairSettingsBytes)
            .doc("pair reservoirs of the rounds before the last");
        r.param("radius", 20.0).min(1).doc("neighbour pair disk radius, pixels");
        r.param("rounds", 1).range(1, 8).doc("spatial rounds of one neighbour pair each");
        r.param("adaptiveSpatial", true)
            .doc(
                "edge pairs search up to edgeCandidates random pairs for one whose pixels both "
                "match (Sec. 5.3, Fig. 10); off: one random pair for every pair");
        r.param("edgeCandidates", 256).range(1, 1024).doc("pairs checked for an edge pair");
        reflectPixelTests(r);
        r.paramEnum("outerShift", "copy", {"copy", "primaryReconnect"})
            .doc(
                "outer shift of the base path to the new pair: film and lens sample copied "
                "(Jacobian 1), or primary-hit reconnection under a thin lens (Area ReSTIR "
                "Sec. 6, lens-space Jacobian; fails without a lens)");
        r.paramEnum("mis", "defensivePairwise", {"defensivePairwise", "balance"})
            .doc(
                "resampling MIS of the current and the neighbour pair: defensive pairwise (the "
                "current sample keeps at least half its weight; ReSTIRPTSpatial's default) or "
                "the generalized balance heuristic");
        r.paramEnum("ablation", "none", {"none", "dropOuterJacobian", "reuseAcrossSigns"})
            .doc(
                "biased variants the tests must detect: the outer shift's Jacobian left out "
                "(lens or, with measure = solidAngle, reconnection), or the neighbour's "
                "reservoir of the other sign reused");
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/gradient_domain/paired_spatial.comp");
    }
    void execute(ExecuteContext& ctx) override {
        auto counters = mCounters.reset(ctx.gpu(), ctx.cmd());
        restir::dispatchSpatialRounds(*this, *mPipeline, ctx, param<int>("rounds"),
                                      ctx.buffer("pairs"), ctx.buffer("pairsOut"),
                                      ctx.scratchBuffer("pingPong"),
                                      [&](gpu::Bindings& b, const std::shared_ptr<gpu::Buffer>& src,
                                          const std::shared_ptr<gpu::Buffer>& dst) {
                                          b.set("PairsIn", src)
                                              .set("PairsOut", dst)
                                              .set("PrimaryIn", ctx.buffer("primary"))
                                              .set("FeaturesIn", ctx.buffer("features"))
                                              .set("RestirCounters", counters);
                                      });
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
};

class PairedPixelResolvePass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputBuffer("pairs").doc("final pair reservoirs (PairedPixelSpatial.pairsOut)");
        r.inputBuffer("reservoirs")
            .doc("final primal reservoirs (Area ReSTIR: ReSTIRPTSpatial.reservoirsOut)");
        r.inputBuffer("primary").doc("ReSTIRPTInitial.primary");
        gradient::reflectGradientImages(r, "the primal reservoirs' F W");
        r.paramEnum("ablation", "none", {"none", "flipGradientSign"})
            .doc("biased variant the tests must detect: the gradients' sign flipped");
    }
    void compile(ShaderLibrary& shaders) override {
        for (int color = 0; color < 2; ++color)
            mPipeline[color] =
                compileKernel(*this, shaders, "passes/gradient_domain/paired_resolve.comp",
                              {{"HAS_COLOR", color ? "1" : "0"}});
    }
    void execute(ExecuteContext& ctx) override {
        bool color = ctx.has("color");
        gpu::Bindings b;
        ctx.scene().bind(b);
        b.set("PairsIn", ctx.buffer("pairs"))
            .set("ReservoirsIn", ctx.buffer("reservoirs"))
            .set("PrimaryIn", ctx.buffer("primary"))
            .set("primalImage", ctx.texture("primal"))
            .set("dxImage", ctx.texture("dx"))
            .set("dyImage", ctx.texture("dy"))
            .set("directImage", ctx.texture("direct"));
        if (color) b.set("colorImage", ctx.texture("color"));
        KernelParams(*this, *mPipeline[color], ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline[2];
};

LOOM_REGISTER_PASS(PairedPixelInitialPass, "PairedPixelInitial",
                   "Gradient-domain ReSTIR PT: paired-pixel reservoirs from the two pixels' "
                   "initial path candidates, per sign with positivization");
LOOM_REGISTER_PASS(PairedPixelTemporalPass, "PairedPixelTemporal",
                   "Gradient-domain ReSTIR PT: temporal reuse of pair reservoirs through "
                   "fractional motion vectors");
LOOM_REGISTER_PASS(PairedPixelSpatialPass, "PairedPixelSpatial",
                   "Gradient-domain ReSTIR PT: spatial reuse between pixel pairs, outer and "
                   "inner shifts, adaptive search for edge pairs");
LOOM_REGISTER_PASS(PairedPixelResolvePass, "PairedPixelResolve",
                   "Gradient-domain ReSTIR PT: gradient images from the pair reservoirs, the "
                   "primal from Area ReSTIR, the directly seen emission apart");

}  // namespace loom
