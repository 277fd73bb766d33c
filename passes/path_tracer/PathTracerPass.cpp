// PathTracer: the reference estimator (NEE + BSDF sampling with MIS, Russian roulette, thin
// lens, camera motion blur) with AOVs. See README.md.
#include <fmt/format.h>

#include <algorithm>

#include "core/gpu/CounterBuffer.h"
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "core/util/Log.h"

namespace loom {

class PathTracerPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputTexture("vbuffer", gpu::Format::RGBA32UI)
            .optional()
            .doc("GBuffer.vbuffer: primary hits of the first sample (not re-traced)");
        r.inputTexture("sample", gpu::Format::RGBA32F)
            .optional()
            .doc("GBuffer.sample: film and lens sample of those hits");
        r.outputTexture("color", gpu::Format::RGBA32F).doc("radiance, mean of spp samples");
        r.outputTexture("albedo", gpu::Format::RGBA32F).optional().doc("first-hit reflectance");
        r.outputTexture("normal", gpu::Format::RGBA32F).optional().doc("first-hit shading normal");
        r.outputTexture("direct", gpu::Format::RGBA32F)
            .optional()
            .doc("emission seen directly + one-bounce lighting");
        r.outputTexture("indirect", gpu::Format::RGBA32F).optional().doc("color - direct");
        r.param("samplesPerPixel", 1).range(1, 4096).doc("paths per pixel per frame");
        r.param("maxBounces", 9).range(0, 64).doc("scattering events per path (1 = direct only)");
        r.param("rrDepth", 5).range(1, 64).doc("Russian roulette after this many bounces");
        r.paramEnum("strategy", "mis", {"mis", "bsdf", "nee"})
            .doc("NEE+BSDF with MIS, BSDF sampling only, or light sampling only");
        r.paramEnum("misHeuristic", "power", shaderEnum("MIS_HEURISTIC"))
            .doc("Veach 1997 Sec. 9.2");
        r.param("motionBlur", true).doc("sample time over the shutter (camera and moving shapes)");
        r.param("clamp", 0.0).min(0).doc("clamp path radiance (0 = off; biased, previews only)");
    }
    void execute(ExecuteContext& ctx) override {
        const auto& scene = ctx.scene();
        ShaderDefines defines;
        for (const char* port : {"albedo", "normal", "direct", "indirect", "vbuffer", "sample"}) {
            std::string name = fmt::format("HAS_{}", port);
            for (auto& c : name) c = char(std::toupper(c));
            defines[name] = std::string(ctx.has(port) ? "1" : "0");
        }
        auto pipeline =
            compileKernel(*this, ctx.shaders(), "passes/path_tracer/path_tracer.comp", defines);
        auto rayCounter = mRayCounter.reset(ctx.gpu(), ctx.cmd());
        gpu::Bindings b;
        scene.bind(b);
        b.set("RayCounter", rayCounter);
        b.set("colorImage", ctx.texture("color"));
        for (auto [port, glsl] : {std::pair{"albedo", "albedoImage"},
                                  {"normal", "normalImage"},
                                  {"direct", "directImage"},
                                  {"indirect", "indirectImage"},
                                  {"vbuffer", "vbufferImage"},
                                  {"sample", "sampleImage"}})
            if (ctx.has(port)) b.set(glsl, ctx.texture(port));
        uint32_t spp = uint32_t(param<int>("samplesPerPixel"));
        uint32_t maxBounces = uint32_t(param<int>("maxBounces"));
        // lavapipe stops a loop after 65535 iterations per invocation (bvh.glsl): split the
        // frame's samples so that a dispatch stays far below that, at 2 rays per bounce and up
        // to kStepsPerRay traversal steps per ray; frameCompleted checks what actually ran.
        constexpr uint32_t kStepsPerRay = 64, kStepBudget = 32768;
        uint32_t perDispatch = std::max(1u, kStepBudget / (2 * (maxBounces + 1) * kStepsPerRay));
        for (uint32_t base = 0; base < spp; base += perDispatch) {
            if (base > 0) ctx.cmd().barrier();
            KernelParams(*this, *pipeline, ctx)
                .set("dispatchSamples", std::min(perDispatch, spp - base))
                .set("sampleBase", base)
                .dispatch(ctx, b, ctx.width(), ctx.height());
        }
    }
    void frameCompleted(gpu::Context& gpu) override {
        mRayCounter.read(gpu);
        // A traversal that reached lavapipe's loop limit was cut short: the image is wrong.
        if (mRayCounter[1] >= 65535u - 16u && !mWarnedLoopLimit) {
            logWarning(
                "PathTracer: an invocation ran {} BVH traversal steps in one dispatch, "
                "at lavapipe's loop limit (65535): some rays were cut short and the image "
                "is wrong; lower maxBounces or use a GPU device",
                mRayCounter[1]);
            mWarnedLoopLimit = true;
        }
    }
    std::map<std::string, double> stats() const override {
        return {{"rays", mRayCounter[0]}, {"maxTraversalSteps", mRayCounter[1]}};
    }

private:
    gpu::CounterBuffer<2> mRayCounter{"RayCounter"};
    bool mWarnedLoopLimit = false;
};

LOOM_REGISTER_PASS(PathTracerPass, "PathTracer",
                   "Reference path tracer: NEE + BSDF sampling with MIS, RR, DOF, motion blur");

}  // namespace loom
