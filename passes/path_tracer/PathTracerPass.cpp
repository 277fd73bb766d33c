// PathTracer: the reference estimator (NEE + BSDF sampling with MIS, Russian roulette, thin
// lens, camera motion blur) with AOVs. See README.md.
#include <fmt/format.h>

#include <algorithm>

#include "core/gpu/CounterBuffer.h"
#include "core/gpu/WorkList.h"
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
        r.paramEnum("sampler", "independent", {"independent", "sobol"})
            .doc(
                "random numbers: independent per draw (hashes), or Owen-scrambled Sobol points "
                "padded per dimension (Burley 2020; pbrt-v4's PaddedSobolSampler), stratified "
                "over a pixel's samples");
        r.param("motionBlur", true).doc("sample time over the shutter (camera and moving shapes)");
        r.param("clamp", 0.0).min(0).doc("clamp path radiance (0 = off; biased, previews only)");
        r.paramEnum("schedule", "megakernel", {"megakernel", "wavefront"})
            .doc(
                "one invocation runs whole paths, or paths advance a vertex per dispatch over "
                "compacted lists, shadow rays in dispatches of their own (same image)");
        r.param("wavefrontDepth", 8)
            .range(0, 64)
            .doc(
                "wavefront: bounce dispatches before the last one runs the paths left to their "
                "end");
    }
    void execute(ExecuteContext& ctx) override {
        const auto& scene = ctx.scene();
        ShaderDefines defines;
        for (const char* port : {"albedo", "normal", "direct", "indirect", "vbuffer", "sample"}) {
            std::string name = fmt::format("HAS_{}", port);
            for (auto& c : name) c = char(std::toupper(c));
            defines[name] = std::string(ctx.has(port) ? "1" : "0");
        }
        if (param<std::string>("sampler") == "sobol") defines["RNG_SOBOL"] = std::string("1");
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
        // Each chunk has its own random stream, in both schedules.
        constexpr uint32_t kStepsPerRay = 64, kStepBudget = 32768;
        uint32_t perDispatch = std::max(1u, kStepBudget / (2 * (maxBounces + 1) * kStepsPerRay));
        if (param<std::string>("schedule") == "wavefront") {
            executeWavefront(ctx, b, defines, spp, perDispatch);
            return;
        }
        auto pipeline =
            compileKernel(*this, ctx.shaders(), "passes/path_tracer/path_tracer.comp", defines);
        for (uint32_t base = 0; base < spp; base += perDispatch) {
            if (base > 0) ctx.cmd().barrier();
            KernelParams(*this, *pipeline, ctx)
                .set("dispatchSamples", std::min(perDispatch, spp - base))
                .set("sampleBase", base)
                .dispatch(ctx, b, ctx.width(), ctx.height());
        }
    }
    // The wavefront schedule (path_tracer_wavefront.comp): per sample, a generate dispatch,
    // bounce and shadow dispatches over the lists the kernels compact, a finish dispatch.
    void executeWavefront(ExecuteContext& ctx, gpu::Bindings& b, const ShaderDefines& defines,
                          uint32_t spp, uint32_t perDispatch) {
        auto stage = [&](int s) {
            ShaderDefines d = defines;
            d["PT_STAGE"] = std::to_string(s);
            return compileKernel(*this, ctx.shaders(),
                                 "passes/path_tracer/path_tracer_wavefront.comp", d);
        };
        auto generate = stage(0), bounce = stage(1), shadow = stage(2), finish = stage(3);
        uint64_t pixels = uint64_t(ctx.width()) * ctx.height();
        if (mWavefrontPixels != pixels) {
            constexpr uint64_t kPathBytes = 16 * 16;  // WavefrontPath
            mPaths = ctx.gpu().createBuffer(pixels * kPathBytes, "WavefrontPaths");
            mShadows = ctx.gpu().createBuffer(48 + 2 * 4 * pixels, "WavefrontShadows");
            mItems = ctx.gpu().createBuffer(8 * pixels, "WorkListItems");
            mWavefrontPixels = pixels;
        }
        b.set("WavefrontPaths", mPaths).set("WavefrontShadows", mShadows);
        auto& cmd = ctx.cmd();
        mWork.reset(ctx.gpu(), cmd);  // creates its buffers on first use, before binding them
        mWork.bind(b, mItems);
        uint32_t maxBounces = uint32_t(param<int>("maxBounces"));
        // Bounce dispatch k sees paths of depth k; the last one runs them to their end.
        uint32_t rounds = std::min(uint32_t(param<int>("wavefrontDepth")), maxBounces);
        for (uint32_t base = 0; base < spp; base += perDispatch) {
            uint32_t samples = std::min(perDispatch, spp - base);
            for (uint32_t s = 0; s < samples; ++s) {
                auto params = [&](gpu::ComputePipeline& p, uint32_t round) {
                    KernelParams k(*this, p, ctx);
                    k.set("dispatchSamples", samples)
                        .set("sampleBase", base)
                        .set("sampleIndex", s)
                        .set("bounceRound", round)
                        .set("finishPaths", uint32_t(round == rounds));
                    return k;
                };
                if (base + s > 0) {
                    cmd.barrier();
                    mWork.reset(ctx.gpu(), cmd);
                }
                params(*generate, 0).dispatch(ctx, b, ctx.width(), ctx.height());
                for (uint32_t k = 0; k <= rounds; ++k) {
                    cmd.barrier();
                    params(*bounce, k)
                        .dispatchIndirect(ctx, b, mWork.args(), gpu::WorkList::argsOffset(int(k)));
                    if (k == rounds) break;
                    cmd.barrier();
                    params(*shadow, k).dispatchIndirect(ctx, b, *mShadows, 16 + 16 * (k % 2));
                }
                cmd.barrier();
                params(*finish, rounds).dispatch(ctx, b, ctx.width(), ctx.height());
            }
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
    gpu::WorkList mWork;
    std::shared_ptr<gpu::Buffer> mPaths, mShadows, mItems;
    uint64_t mWavefrontPixels = 0;
    bool mWarnedLoopLimit = false;
};

LOOM_REGISTER_PASS(PathTracerPass, "PathTracer",
                   "Reference path tracer: NEE + BSDF sampling with MIS, RR, DOF, motion blur");

}  // namespace loom
