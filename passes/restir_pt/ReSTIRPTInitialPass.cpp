// ReSTIRPTInitial: initial path candidates of ReSTIR PT (Lin et al. 2022). See README.md.
#include "core/gpu/CounterBuffer.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "passes/restir_pt/PathReservoir.h"

namespace loom {

class ReSTIRPTInitialPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputTexture("vbuffer", gpu::Format::RGBA32UI).doc("GBuffer.vbuffer: primary hits");
        r.inputTexture("sample", gpu::Format::RGBA32F).doc("GBuffer.sample: film and lens sample");
        r.outputBuffer("reservoirs")
            .bytesPerPixel(restir::kReservoirBytes, restir::kSettingsBytes)
            .doc("path reservoirs (settings header + one PathReservoir per pixel)");
        r.outputBuffer("primary")
            .bytesPerPixel(restir::kPrimaryHitBytes)
            .doc("per-pixel primary hit (camera vertex + triangle/barycentrics)");
        r.param("candidates", 1).range(1, 64).doc("paths per pixel resampled into the reservoir");
        r.param("maxBounces", 9).range(1, 14).doc("scattering events per path (PathTracer's)");
        r.param("rrDepth", 5)
            .range(1, 64)
            .doc(
                "Russian roulette from this vertex on, after the reconnection vertex only "
                "(PathTracer's rrDepth)");
        r.paramEnum("shift", "hybrid", shaderEnum("SHIFT"))
            .doc("shift mapping used by all later reuse (Lin et al. Sec. 6)");
        r.param("roughnessThreshold", 0.2)
            .range(0, 1)
            .doc(
                "hybrid shift: both reconnection endpoints need linear roughness sqrt(alpha) "
                "above this");
        r.param("distanceThreshold", 0.1)
            .min(0)
            .doc("hybrid shift: minimum reconnection segment length (near-field distance)");
        r.paramEnum("misHeuristic", "power", shaderEnum("MIS_HEURISTIC"))
            .doc("NEE/BSDF MIS inside a path, as PathTracer");
        r.paramEnum("reuse", "path", {"path", "area"})
            .doc(
                "path: the primary hit is fixed per pixel (ReSTIR PT); area: film and lens "
                "samples are part of the sample and are reused too (Area ReSTIR)");
        r.param("motionBlur", false)
            .doc(
                "reuse = area: each candidate also samples a shutter time (PathTracer's uniform "
                "shutter fraction) that belongs to the sample: the camera and moving shapes "
                "blurred (pair with GBuffer.motionBlur = true for the directly seen emission)");
        r.param("coveredMaxChain", 0)
            .range(0, 4)
            .doc(
                "> 0: leave out the paths a caustic estimator (SMS, psms) produces, with chains "
                "of up to this many specular vertices (its maxChain), for every later reuse "
                "too; 0: every path");
        r.param("coveredDepth", 0)
            .range(0, 8)
            .doc(
                "with coveredMaxChain: the deepest receiver, behind this many specular "
                "vertices (0: primary hits; the caustic estimator's receiverDepth)");
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/restir_pt/initial.comp");
    }
    void execute(ExecuteContext& ctx) override {
        auto rayCounter = mRayCounter.reset(ctx.gpu(), ctx.cmd());
        gpu::Bindings b;
        ctx.scene().bind(b);
        b.set("vbufferImage", ctx.texture("vbuffer"))
            .set("sampleImage", ctx.texture("sample"))
            .set("ReservoirsOut", ctx.buffer("reservoirs"))
            .set("PrimaryOut", ctx.buffer("primary"))
            .set("RayCounter", rayCounter);
        KernelParams(*this, *mPipeline, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }
    void frameCompleted(gpu::Context& gpu) override { mRayCounter.read(gpu); }
    std::map<std::string, double> stats() const override {
        return {{"rays", mRayCounter[0]}, {"maxTraversalSteps", mRayCounter[1]}};
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
    gpu::CounterBuffer<2> mRayCounter{"RayCounter"};
};

LOOM_REGISTER_PASS(
    ReSTIRPTInitialPass, "ReSTIRPTInitial",
    "ReSTIR PT initial candidates: path tree from the GBuffer, RIS into a path reservoir");

}  // namespace loom
