// SpecularManifoldSampling: caustics by specular manifold sampling (Zeltner et al. 2020),
// unbiased or biased, or MNEE (Hanika et al. 2015), at the receivers a path tracer's camera
// path reaches through purely specular surfaces; the path tracer leaves out exactly the paths
// SMS produces. See README.md.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/glm.hpp>

#include "core/gpu/CounterBuffer.h"
#include "core/gpu/WorkList.h"
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneGpu.h"
#include "core/util/Log.h"
#include "passes/sms/ManifoldParams.h"

namespace loom {

namespace {

constexpr uint64_t kPixelBytes = 144;        // SmsPixel (sms_common.glsl)
constexpr uint64_t kSolutionSetBytes = 512;  // SmsSolutionSet: 32 directions
constexpr int kMaxBiasedTrials = 32;

enum Counter { kSamples, kSolved, kIterations, kTrials, kBernoulli, kCapped, kMaxSteps, kRays };

}  // namespace

class SpecularManifoldSamplingPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.outputTexture("color", gpu::Format::RGBA32F)
            .doc("full image: path tracer without the SMS-covered paths + caustic");
        r.outputTexture("caustic", gpu::Format::RGBA32F)
            .optional()
            .doc("the SMS estimate alone (caustics at receivers, through the specular prefix)");
        r.outputTexture("stats", gpu::Format::RGBA32F)
            .optional()
            .doc("per pixel: Newton iterations, solution found, trials, SMS estimate taken");
        r.scratchTexture("path").doc("the path tracer's part");
        const uint64_t receivers = uint64_t(maxReceivers());
        r.scratchBuffer("pixels")
            .bytesPerPixel(kPixelBytes * receivers)
            .doc("estimator state per pixel and receiver");
        r.scratchBuffer("solutions")
            .bytesPerPixel(kSolutionSetBytes * receivers)
            .doc("biased SMS: unique solutions found per pixel and receiver");
        r.scratchBuffer("active")
            .bytesPerPixel(8 * receivers)
            .doc("two lists of the estimates that still run (trial dispatches take them packed)");
        r.paramEnum("estimator", "unbiased", {"unbiased", "biased", "mnee"})
            .doc(
                "unbiased SMS (Bernoulli trials), biased SMS (unique solutions of M trials), or "
                "MNEE (one walk from the straight line to the light, or from a reflective "
                "caster's bounding-box centre)");
        reflectManifoldWalk(r);
        r.param("maxTrials", 10000000)
            .min(1)
            .doc("unbiased: Bernoulli trials before the cap (reference default 1e7)");
        r.paramEnum("trialCap", "drop", {"drop", "keep"})
            .doc("at the cap: drop the sample (reference code) or keep it with K = maxTrials");
        r.param("biasedTrials", 4).range(1, kMaxBiasedTrials).doc("biased: trials M per estimate");
        reflectCausticPath(r, 64);
        reflectReceiverDepth(r);
        r.param("maxReceivers", 1)
            .range(1, 8)
            .doc(
                "SMS estimates per camera path: at its first maxReceivers vertices with a smooth "
                "lobe that are receivers (1: the first; more: caustics seen behind diffuse "
                "bounces, as the reference integrator estimates at every depth)");
        r.param("roughCasters", true)
            .doc(
                "walk rough conductors and dielectrics about sampled offset normals (Zeltner et "
                "al. Sec. 5.3); false leaves their caustics to the path tracer");
    }
    void execute(ExecuteContext& ctx) override {
        const auto& scene = ctx.scene();
        buildCasters(ctx);
        const std::string receivers = std::to_string(maxReceivers());
        ShaderDefines defines{{"HAS_STATS", ctx.has("stats") ? "1" : "0"},
                              {"HAS_CAUSTIC", ctx.has("caustic") ? "1" : "0"},
                              {"MANIFOLD_MAX_RECEIVERS", receivers}};
        auto resolve = compileKernel(*this, ctx.shaders(), "passes/sms/sms_resolve.comp", defines);
        // Chains sized to maxChain: the walk state lives in registers or spills per lane, and
        // on lavapipe 2 vertices instead of 4 make the trials 2.6x faster (same image).
        // Environment lights end chains too (the path part leaves those paths out as well).
        ShaderDefines chain{{"MANIFOLD_MAX_VERTICES", std::to_string(param<int>("maxChain"))},
                            {"MANIFOLD_ENVIRONMENT_CHAINS", "1"},
                            {"MANIFOLD_MAX_RECEIVERS", receivers}};
        // Rough casters' offset normals, compiled in only where the scene has such casters
        // (llvmpipe runs untaken branches masked).
        if (mRoughCasters && param<bool>("roughCasters"))
            chain.insert_or_assign("MANIFOLD_ROUGH_CASTERS", std::string("1"));
        auto path = compileKernel(*this, ctx.shaders(), "passes/sms/sms_path.comp", chain);
        auto trials = compileKernel(*this, ctx.shaders(), "passes/sms/sms_trials.comp", chain);
        auto counters = mCounters.reset(ctx.gpu(), ctx.cmd());
        mWork.reset(ctx.gpu(), ctx.cmd());
        float minSegment = 1e-4f * std::max(scene.boundingSphere().w, 1e-6f);

        gpu::Bindings b;
        scene.bind(b);
        b.set("ManifoldCasters", mCasters)
            .set("SmsMneeSeeds", mMneeSeeds)
            .set("SmsPixels", ctx.scratchBuffer("pixels"))
            .set("SmsSolutions", ctx.scratchBuffer("solutions"))
            .set("SmsCounters", counters)
            .set("pathImage", ctx.scratchTexture("path"))
            .set("colorImage", ctx.texture("color"));
        if (ctx.has("caustic")) b.set("causticImage", ctx.texture("caustic"));
        if (ctx.has("stats")) b.set("statsImage", ctx.texture("stats"));
        mWork.bind(b, ctx.scratchBuffer("active"));
        auto params = [&](gpu::ComputePipeline& p) {
            KernelParams k(*this, p, ctx);
            k.set("minSegment", minSegment);
            k.set("dispatchIndex", 0u);
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
                "SpecularManifoldSampling: an invocation ran {} BVH steps in one dispatch, at "
                "lavapipe's loop limit (65535): lower stepBudget",
                mCounters[kMaxSteps]);
            mWarnedLoopLimit = true;
        }
        if (mCounters[kCapped] > 0 && !mWarnedCap) {
            logWarning(
                "SpecularManifoldSampling: {} estimates reached the trial cap this frame "
                "(maxTrials or trialDispatches; trialCap = {}): the unbiased estimate is biased "
                "there",
                mCounters[kCapped], param<std::string>("trialCap"));
            mWarnedCap = true;
        }
    }
    void onParamChanged(const std::string&) override { std::fill(mTotals, mTotals + 8, 0.0); }
    // Hong et al. 2025 Table 1 columns, over the frames rendered so far, and this frame's
    // counters.
    std::map<std::string, double> stats() const override {
        auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
        const double* t = mTotals;
        return {{"samples", t[kSamples]},
                {"solutions", t[kSolved]},
                {"successRate", ratio(t[kSolved], t[kSamples])},
                {"iterationsPerSample", ratio(t[kIterations], t[kSamples])},
                {"trialsPerSolution", ratio(t[kBernoulli], t[kSolved])},
                {"iterationsPerSolution", ratio(t[kIterations], t[kSolved])},
                {"walks", t[kTrials]},
                {"capped", t[kCapped]},
                {"rays", t[kRays]},
                {"maxTraversalSteps", double(mCounters[kMaxSteps])}};
    }

private:
    // reflect() runs before the parameters exist (to declare them): the default then.
    int maxReceivers() const {
        return params().count("maxReceivers") ? param<int>("maxReceivers") : 1;
    }
    // Seeds: caster triangles (caustic_caster tags) with an inclusive area CDF, in the GPU
    // triangle order of SceneGpu (shapes in order, each shape's triangles contiguous).
    void buildCasters(ExecuteContext& ctx) {
        const scene::Scene& s = ctx.scene().cpu();
        if (mCasterScene == &s && mCasters) return;
        std::vector<std::pair<uint32_t, double>> tris;
        double total = 0.0;
        uint32_t first = 0;
        bool receivers = false, emitters = false, refractors = false;
        mRoughCasters = false;
        // MNEE's seeds (SmsMneeSeeds): [0].x = 1 when a refractive caster exists (the straight
        // line to the light), then the bounding-box centre of each reflective caster.
        std::vector<glm::vec4> mneeSeeds(1, glm::vec4(0.0f));
        for (const auto& shape : s.shapes) {
            const auto& mesh = s.meshes[shape.mesh];
            if (shape.flags & scene::kCausticReceiver) receivers = true;
            if ((shape.flags & scene::kCausticEmitter) && glm::length(shape.emission) > 0)
                emitters = true;
            if (shape.flags & (scene::kCausticCasterReflect | scene::kCausticCasterRefract)) {
                glm::mat4 m = scene::shapeToWorldAt(shape, 0.0f);
                glm::vec3 lo(1e30f), hi(-1e30f);
                for (const glm::vec3& p : mesh.positions) {
                    glm::vec3 w = glm::vec3(m * glm::vec4(p, 1.0f));
                    lo = glm::min(lo, w);
                    hi = glm::max(hi, w);
                }
                scene::BsdfType type = s.materials[shape.material].type;
                bool rough = type == scene::BsdfType::RoughConductor ||
                             type == scene::BsdfType::RoughDielectric;
                if (rough) mRoughCasters = true;
                if ((type == scene::BsdfType::Conductor ||
                     type == scene::BsdfType::RoughConductor) &&
                    !mesh.positions.empty())
                    mneeSeeds.push_back(glm::vec4(0.5f * (lo + hi), 0.0f));
                else
                    refractors = true;
                for (size_t t = 0; t < mesh.indices.size(); ++t) {
                    glm::uvec3 i = mesh.indices[t];
                    glm::vec3 a = glm::vec3(m * glm::vec4(mesh.positions[i.x], 1.0f));
                    glm::vec3 b = glm::vec3(m * glm::vec4(mesh.positions[i.y], 1.0f));
                    glm::vec3 c = glm::vec3(m * glm::vec4(mesh.positions[i.z], 1.0f));
                    double area = 0.5 * glm::length(glm::cross(b - a, c - a));
                    if (area > 0) {
                        total += area;
                        tris.push_back({first + uint32_t(t), total});
                    }
                }
            }
            first += uint32_t(mesh.indices.size());
        }
        for (const auto& l : s.lights)
            if (l.flags & scene::kCausticEmitter) emitters = true;
        const std::string where = "scene '" + s.sourceFile + "'";  // the graph adds the pass
        if (tris.empty())
            throw UserError(where + ": no caustic casters (tag specular shapes caustic_caster)");
        if (!receivers)
            throw UserError(where + ": casters but no caustic receivers (tag caustic_receiver)");
        if (!emitters)
            throw UserError(where + ": no caustic emitters (tag a light caustic_emitter)");
        std::vector<glm::uvec2> data;
        for (auto& [tri, cdf] : tris) {
            float f = float(cdf / total);
            uint32_t bits;
            std::memcpy(&bits, &f, 4);
            data.push_back({tri, bits});
        }
        data.back().y = 0x3f800000u;  // exactly 1
        mCasters = ctx.gpu().createBuffer(data.size() * sizeof(glm::uvec2), "ManifoldCasters");
        ctx.gpu().uploadBuffer(*mCasters, data.data(), data.size() * sizeof(glm::uvec2));
        mneeSeeds[0].x = refractors ? 1.0f : 0.0f;
        mMneeSeeds = ctx.gpu().createBuffer(mneeSeeds.size() * sizeof(glm::vec4), "SmsMneeSeeds");
        ctx.gpu().uploadBuffer(*mMneeSeeds, mneeSeeds.data(), mneeSeeds.size() * sizeof(glm::vec4));
        mCasterScene = &s;
    }

    std::shared_ptr<gpu::Buffer> mCasters, mMneeSeeds;
    gpu::WorkList mWork;
    const scene::Scene* mCasterScene = nullptr;
    gpu::CounterBuffer<8> mCounters{"SmsCounters"};
    double mTotals[8] = {};
    bool mWarnedLoopLimit = false, mWarnedCap = false;
    bool mRoughCasters = false;  // the scene has rough conductor or dielectric casters
};

LOOM_REGISTER_PASS(SpecularManifoldSamplingPass, "SpecularManifoldSampling",
                   "Caustics by specular manifold sampling (unbiased, biased) or MNEE, with a "
                   "path tracer that leaves out the paths they produce");

}  // namespace loom
