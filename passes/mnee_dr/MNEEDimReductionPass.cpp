// MNEEDimReduction: caustics through one specular interface by manifold next-event estimation
// with dimension reduction (Granizo-Hidalgo & Holzschuch 2024), beside the reference path
// tracer without the paths it covers. See README.md.
#include <fmt/format.h>

#include <algorithm>
#include <glm/glm.hpp>

#include "core/gpu/CounterBuffer.h"
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"
#include "core/util/Log.h"
#include "passes/sms/ManifoldParams.h"

namespace loom {

namespace {

// MneeDrCounters (mnee_dr_common.glsl): walks, one per COPLANAR_* status, triangles, bisections,
// largest BVH step count, rays.
constexpr int kWalks = 0, kStatus = 1, kTriangles = 9, kBisections = 10, kMaxSteps = 11, kRays = 12,
              kCounters = 16;
const char* const kStatusNames[] = {
    "solved",     "noStart", "boundary", "cap", "totalInternalReflection",
    "degenerate", "noRoot",  "occluded"};

}  // namespace

class MNEEDimReductionPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.outputTexture("color", gpu::Format::RGBA32F)
            .doc("full image: path tracer without the covered paths + caustic");
        r.outputTexture("caustic", gpu::Format::RGBA32F)
            .optional()
            .doc("the MNEE estimate alone (caustics at the receivers)");
        r.outputTexture("stats", gpu::Format::RGBA32F)
            .optional()
            .doc("per pixel: triangles crossed, bisection steps, solution found, walk run");
        r.scratchTexture("path").doc("the path tracer's part");
        r.param("maxTriangles", 1000)
            .range(1, 1000000)
            .doc("triangles a walk may enter, both directions together (the paper sets none)");
        r.param("maxBisections", 40).range(1, 64).doc("bisection steps per bracket");
        r.param("bisectionTolerance", 1e-5)
            .range(1e-9, 0.1)
            .doc(
                "bisection ends when its bracket is below this times the triangle's longest "
                "edge");
        r.param("bothDirections", true)
            .doc("when the walk fails one way from the start point, walk the other way");
        reflectReceiverDepth(r);
        reflectCoveredPathTracer(r);
    }

    void execute(ExecuteContext& ctx) override {
        checkScene(ctx.scene().cpu());
        ShaderDefines defines{{"HAS_STATS", ctx.has("stats") ? "1" : "0"},
                              {"HAS_CAUSTIC", ctx.has("caustic") ? "1" : "0"},
                              {"MANIFOLD_MAX_VERTICES", "1"}};
        auto path = compileKernel(*this, ctx.shaders(), "passes/mnee_dr/mnee_dr_path.comp");
        auto caustic =
            compileKernel(*this, ctx.shaders(), "passes/mnee_dr/mnee_dr_caustic.comp", defines);
        auto counters = mCounters.reset(ctx.gpu(), ctx.cmd());
        gpu::Bindings b;
        ctx.scene().bind(b);
        b.set("MneeDrCounters", counters)
            .set("pathImage", ctx.scratchTexture("path"))
            .set("colorImage", ctx.texture("color"));
        if (ctx.has("caustic")) b.set("causticImage", ctx.texture("caustic"));
        if (ctx.has("stats")) b.set("statsImage", ctx.texture("stats"));
        KernelParams(*this, *path, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
        ctx.cmd().barrier();
        KernelParams(*this, *caustic, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }

    void frameCompleted(gpu::Context& gpu) override {
        mCounters.read(gpu);
        for (int i = 0; i < kCounters; ++i) mTotals[i] += mCounters[i];
        if (mCounters[kMaxSteps] >= 65535u - 16u && !mWarnedLoopLimit) {
            logWarning(
                "MNEEDimReduction: an invocation ran {} BVH steps, at lavapipe's loop limit "
                "(65535): lower maxBounces",
                mCounters[kMaxSteps]);
            mWarnedLoopLimit = true;
        }
    }
    void onParamChanged(const std::string&) override {
        std::fill(mTotals, mTotals + kCounters, 0.0);
    }

    // Over the frames rendered so far: walks, how they ended, and their cost.
    std::map<std::string, double> stats() const override {
        auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
        std::map<std::string, double> s{
            {"walks", mTotals[kWalks]},
            {"successRate", ratio(mTotals[kStatus], mTotals[kWalks])},
            {"trianglesPerWalk", ratio(mTotals[kTriangles], mTotals[kWalks])},
            {"bisectionsPerWalk", ratio(mTotals[kBisections], mTotals[kWalks])},
            {"rays", mTotals[kRays]},
            {"maxTraversalSteps", double(mCounters[kMaxSteps])}};
        for (int i = 0; i < 8; ++i) s[kStatusNames[i]] = mTotals[kStatus + i];
        return s;
    }

private:
    void checkScene(const scene::Scene& s) {
        if (mCheckedScene == &s) return;
        bool casters = false, receivers = false, emitters = false;
        for (const auto& shape : s.shapes) {
            casters |=
                (shape.flags & (scene::kCausticCasterReflect | scene::kCausticCasterRefract)) != 0;
            receivers |= (shape.flags & scene::kCausticReceiver) != 0;
            emitters |= (shape.flags & scene::kCausticEmitter) && glm::length(shape.emission) > 0;
        }
        for (const auto& l : s.lights) emitters |= (l.flags & scene::kCausticEmitter) != 0;
        const std::string where = "scene '" + s.sourceFile + "'";
        if (!casters)
            throw UserError(where + ": no caustic casters (tag specular shapes caustic_caster)");
        if (!receivers)
            throw UserError(where + ": casters but no caustic receivers (tag caustic_receiver)");
        if (!emitters)
            throw UserError(where + ": no caustic emitters (tag a light caustic_emitter)");
        mCheckedScene = &s;
    }

    const scene::Scene* mCheckedScene = nullptr;
    gpu::CounterBuffer<kCounters> mCounters{"MneeDrCounters"};
    double mTotals[kCounters] = {};
    bool mWarnedLoopLimit = false;
};

LOOM_REGISTER_PASS(MNEEDimReductionPass, "MNEEDimReduction",
                   "Caustics through one specular interface by MNEE with dimension reduction "
                   "(Granizo-Hidalgo & Holzschuch 2024): a walk along the coplanarity curve, with "
                   "a path tracer that leaves out the paths it produces");

}  // namespace loom
