// PoissonReconstruct: screened Poisson reconstruction of an image from its primal estimate and
// its forward-difference gradients, L2 (conjugate gradients, multigrid-preconditioned CG or
// Jacobi) or L1 (IRLS around the L2 solver). See README.md.
#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"

namespace loom {

namespace {

constexpr uint32_t kNoSlot = 0xffffffffu;  // POISSON_NO_SLOT
constexpr uint64_t kStepBytes = 80;        // PoissonStep, poisson_common.glsl
constexpr uint64_t kVec = 16;              // one vec4
// Spare elements for the ceil() overhead of small multigrid pyramids.
constexpr uint64_t kSpareElements = 4096;
constexpr uint32_t kCoarsestSweeps = 2;
// Indirect dispatch arguments (uvec4 each): level l's 8x8 groups at entry l, one group for
// the reduce at kReduceArgs. A solve's kernels read them from PoissonDispatch, which the
// reduce of r.r sets to these or to zero groups once the solve has converged: skipped steps
// then cost no invocations (on lavapipe an invocation that returns at once still costs).
constexpr uint32_t kHalfArgs = 32;    // POISSON_HALF_ARGS: + level, half the columns
constexpr uint32_t kReduceArgs = 64;  // POISSON_REDUCE_ARGS
constexpr uint32_t kPlotWidth = 256, kPlotHeight = 128;

enum Field : uint32_t { kNone, kRR, kRZ, kPAp, kBB, kRRasRZ };  // poisson_reduce.comp
constexpr uint32_t kFieldSums = kRR;  // the weights record: sums in rr (info unused)

struct Level {
    uint32_t w, h;
    uint64_t offset;  // in elements, within a pyramid
    uint64_t size() const { return uint64_t(w) * h; }
};

}  // namespace

class PoissonReconstructPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.inputTexture("primal", gpu::Format::RGBA32F).doc("primal estimate f");
        r.inputTexture("dx", gpu::Format::RGBA32F)
            .doc("horizontal gradient g_x(p) = x(p + e_x) - x(p); the last column is unused");
        r.inputTexture("dy", gpu::Format::RGBA32F)
            .doc("vertical gradient g_y(p) = x(p + e_y) - x(p); the last row is unused");
        r.outputTexture("output", gpu::Format::RGBA32F).doc("the reconstructed image");
        r.outputTexture("residualPlot", gpu::Format::RGBA32F)
            .fixedSize(kPlotWidth, kPlotHeight)
            .doc("log10 relative residual per solver step (10^0 top, 10^-8 bottom)");
        r.outputBuffer("history")
            .bytes(kStepBytes * solves() * stepsPerSolve())
            .optional()
            .doc(
                "per solve (1 for l2, irlsIterations for l1): the weights record, then steps "
                "0..iterations, each {vec4 rr, rz, pAp, bb; uvec4 info} (poisson_common.glsl)");
        // The kernels' step records live in a buffer of the pass's own: an output nobody reads
        // is transient memory that later passes of the frame may reuse before frameCompleted()
        // reads the statistics from it.
        SizeRule steps;
        steps.mode = SizeRule::Mode::Fixed;
        steps.bytes = kStepBytes * solves() * stepsPerSolve();
        r.persistentBuffer("steps", steps, "the step records (copied to history when it is used)");
        r.paramEnum("solver", "l2", {"l2", "l1"})
            .doc("l2: min ||W(b - Px)||_2 in one linear solve; l1: IRLS, the first solve l2");
        r.param("alpha", 0.2)
            .range(1e-3, 100)
            .doc("weight of the primal rows, P x = [alpha x; D_x x; D_y x]");
        r.paramEnum("linearSolver", "cg", {"cg", "multigrid", "jacobi"})
            .doc(
                "cg: conjugate gradients (the paper's); multigrid: CG preconditioned by a "
                "symmetric V-cycle (red-black Gauss-Seidel); jacobi: Jacobi iterations, for "
                "comparison");
        r.param("iterations", 50).range(1, 1000).doc("solver steps per linear solve");
        r.param("irlsIterations", 20).range(1, 64).doc("l1: linear solves (the first is l2)");
        r.param("irlsEpsilon", 0.05)
            .range(1e-8, 10)
            .doc("l1: solve k >= 1 weighs rows by 1 / (||e||_RGB + irlsEpsilon 0.5^(k-1))");
        r.param("tolerance", 0.0)
            .range(0, 1)
            .doc(
                "stop a linear solve once ||r|| / ||b|| is below this in every channel (0: never)");
        r.param("smoothingSweeps", 1)
            .range(1, 8)
            .doc("multigrid: Gauss-Seidel sweeps before and after");
        bool mg = multigrid();
        r.scratchBuffer("vectors")
            .bytesPerPixel(kVec * (mg ? 10 : 5), mg ? kVec * kSpareElements : 0)
            .doc("x, b, r, p, Ap; with multigrid also the pyramids of x, b and r");
        r.scratchBuffer("weights")
            .bytesPerPixel(kVec * (mg ? 2 : 1), mg ? kVec * kSpareElements : 0)
            .doc("per pixel (alpha^2 W^2, W^2 right, W^2 below), per multigrid level");
        // 16 pairs of vec4 per 8x8 workgroup (POISSON_PAIRS_PER_GROUP), plus the partial groups
        // at the right and bottom edges.
        r.scratchBuffer("partials")
            .bytesPerPixel(8, 512 * 4096)
            .doc("per subgroup, partial sums of dot products");
    }
    bool paramChangesPorts(const std::string& name) const override {
        return name == "solver" || name == "iterations" || name == "irlsIterations" ||
               name == "linearSolver";
    }
    void compile(ShaderLibrary& shaders) override {
        auto k = [&](const char* name) {
            return compileKernel(*this, shaders,
                                 fmt::format("passes/gradient_domain/poisson_{}.comp", name));
        };
        mWeights = k("weights");
        mRhs = k("rhs");
        mScaleWeights = k("scale_weights");
        mResidual = k("residual");
        mReduce = k("reduce");
        mDirection = k("direction");
        mApply = k("apply");
        mUpdate = k("update");
        mDot = k("dot");
        mSmooth = k("smooth");
        mRestrict = k("restrict");
        mProlong = k("prolong");
        mCoarsen = k("coarsen");
        mOutput = k("output");
        mPlot = k("plot");
    }

    void execute(ExecuteContext& ctx) override {
        const uint32_t w = ctx.width(), h = ctx.height();
        for (const char* port : {"primal", "dx", "dy"}) {
            auto t = ctx.texture(port);
            if (t->width() != w || t->height() != h)
                throw UserError(
                    fmt::format("input '{}' is {}x{} but the frame is {}x{}; render "
                                "at the images' size",
                                port, t->width(), t->height(), w, h));
        }
        mCtx = &ctx;
        mN = uint64_t(w) * h;
        mGroups = ((w + 7) / 8) * ((h + 7) / 8);
        mHistory = ctx.persistentBuffer("steps");
        mSolves = solves();
        mStepsPerSolve = stepsPerSolve();
        const bool mg = multigrid();
        const bool jacobi = param<std::string>("linearSolver") == "jacobi";
        const uint32_t iterations = uint32_t(param<int>("iterations"));
        mSweeps = uint32_t(param<int>("smoothingSweeps"));

        // Layout: X, B, R, P, Q (finest level), then the pyramids of x (level 0 is z = M^-1 r),
        // b (level 0 unused: the finest b is R) and r.
        mX = 0, mB = mN, mR = 2 * mN, mP = 3 * mN, mQ = 4 * mN;
        mLevels = {{w, h, 0}};
        if (mg)
            while (std::min(mLevels.back().w, mLevels.back().h) > 16) {
                const Level& f = mLevels.back();
                mLevels.push_back({(f.w + 1) / 2, (f.h + 1) / 2, f.offset + f.size()});
            }
        uint64_t pyramid = mLevels.back().offset + mLevels.back().size();
        mMX = 5 * mN, mMB = mMX + pyramid, mMR = mMB + pyramid;
        uint64_t vectors = mg ? mMR + pyramid : 5 * mN;
        if (vectors * kVec > ctx.scratchBuffer("vectors")->size() ||
            pyramid * kVec > ctx.scratchBuffer("weights")->size() ||
            uint64_t(mGroups) * 512 > ctx.scratchBuffer("partials")->size())
            throw UserError(
                fmt::format("PoissonReconstruct: a {}x{} frame does not fit its "
                            "scratch buffers (too thin an image?)",
                            w, h));
        if (mLevels.size() > kHalfArgs)
            throw UserError("PoissonReconstruct: too many multigrid levels");
        std::vector<uint32_t> full(4 * (kReduceArgs + 1), 0u);
        for (size_t l = 0; l < mLevels.size(); ++l) {
            full[4 * l] = (mLevels[l].w + 7) / 8;
            full[4 * l + 1] = (mLevels[l].h + 7) / 8;
            full[4 * l + 2] = 1;
            full[4 * (kHalfArgs + l)] = ((mLevels[l].w + 1) / 2 + 7) / 8;
            full[4 * (kHalfArgs + l) + 1] = (mLevels[l].h + 7) / 8;
            full[4 * (kHalfArgs + l) + 2] = 1;
        }
        full[4 * kReduceArgs] = full[4 * kReduceArgs + 1] = full[4 * kReduceArgs + 2] = 1;
        if (!mArgs) {
            mArgs = ctx.gpu().createBuffer(full.size() * 4, "PoissonDispatch");
            mArgsFull = ctx.gpu().createBuffer(full.size() * 4, "PoissonDispatchFull");
        }
        if (full != mArgsUploaded) {
            ctx.gpu().uploadBuffer(*mArgsFull, full.data(), full.size() * 4);
            mArgsUploaded = full;
        }
        mBind = gpu::Bindings();
        mBind.set("PoissonVectors", ctx.scratchBuffer("vectors"))
            .set("PoissonWeights", ctx.scratchBuffer("weights"))
            .set("PoissonPartials", ctx.scratchBuffer("partials"))
            .set("PoissonHistory", mHistory)
            .set("PoissonDispatch", mArgs)
            .set("PoissonDispatchFull", mArgsFull)
            .set("primalImage", ctx.texture("primal"))
            .set("dxImage", ctx.texture("dx"))
            .set("dyImage", ctx.texture("dy"))
            .set("outputImage", ctx.texture("output"))
            .set("plotImage", ctx.texture("residualPlot"));

        ctx.cmd().fillBuffer(*mHistory, 0);
        ctx.cmd().barrier();
        const double eps0 = param<double>("irlsEpsilon");
        for (uint32_t s = 0; s < mSolves; ++s) {
            const uint32_t weightSlot = s * mStepsPerSolve, s0 = weightSlot + 1;
            // Row weights (uniform, or IRLS from the current x), their sum, b, x0.
            frame(*mWeights)
                .set("epsilon", float(s == 0 ? 1.0 : eps0 * std::pow(0.5, double(s - 1))))
                .set("reweight", s > 0 ? 1u : 0u)
                .set("xOffset", u(mX))
                .dispatch(ctx, mBind, w, h);
            reduce(weightSlot, kNoSlot, weightSlot, kFieldSums, kNone);
            frame(*mRhs)
                .set("weightSlot", weightSlot)
                .set("initialize", s == 0 ? 1u : 0u)
                .set("xOffset", u(mX))
                .set("bOffset", u(mB))
                .dispatch(ctx, mBind, w, h);
            barrier();
            frame(*mScaleWeights).set("weightSlot", weightSlot).dispatch(ctx, mBind, w, h);
            barrier();
            for (size_t l = 0; l + 1 < mLevels.size(); ++l) {
                KernelParams(*this, *mCoarsen, ctx)
                    .setUints("fineSize", &mLevels[l].w, 2)
                    .setUints("coarseSize", &mLevels[l + 1].w, 2)
                    .set("fineOffset", u(mLevels[l].offset))
                    .set("coarseOffset", u(mLevels[l + 1].offset))
                    .dispatch(ctx, mBind, mLevels[l + 1].w, mLevels[l + 1].h);
                barrier();
            }
            // r = b - A x (warm start), its r.r and b.b.
            residual(0, mX, mB, mR, kNoSlot);
            reduce(s0, kNoSlot, s0, mg || jacobi ? kRR : kRRasRZ, kBB);
            for (uint32_t k = 0; k < iterations; ++k) {
                const uint32_t slot = s0 + k;
                if (jacobi) {
                    update(slot, true);
                    barrier();
                    residual(0, mX, mB, mR, slot);
                    reduce(slot + 1, slot, s0, kRR, kNone);
                    continue;
                }
                if (mg) {
                    vcycle(slot);
                    frame(*mDot)
                        .set("slot", slot)
                        .set("aOffset", u(mR))
                        .set("bOffset", u(mMX))
                        .dispatchIndirect(ctx, mBind, *mArgs, 0);
                    reduce(slot, slot, s0, kRZ, kNone);
                }
                frame(*mDirection)
                    .set("slot", slot)
                    .set("first", k == 0 ? 1u : 0u)
                    .set("zOffset", u(mg ? mMX : mR))
                    .set("pOffset", u(mP))
                    .dispatchIndirect(ctx, mBind, *mArgs, 0);
                barrier();
                frame(*mApply)
                    .set("slot", slot)
                    .set("pOffset", u(mP))
                    .set("qOffset", u(mQ))
                    .dispatchIndirect(ctx, mBind, *mArgs, 0);
                reduce(slot, slot, s0, kPAp, kNone);
                update(slot, false);
                reduce(slot + 1, slot, s0, mg ? kRR : kRRasRZ, kNone);
            }
        }
        frame(*mOutput).set("xOffset", u(mX)).dispatch(ctx, mBind, w, h);
        if (auto history = ctx.buffer("history"))
            ctx.cmd().copyBuffer(*mHistory, *history, mHistory->size());
        uint32_t plotSize[2] = {kPlotWidth, kPlotHeight};
        KernelParams(*this, *mPlot, ctx)
            .setUints("plotSize", plotSize, 2)
            .set("solves", mSolves)
            .set("stepsPerSolve", mStepsPerSolve)
            .dispatch(ctx, mBind, kPlotWidth, kPlotHeight);
        mCtx = nullptr;
    }

    void frameCompleted(gpu::Context& gpu) override {
        if (!mHistory) return;
        std::vector<float> steps(mHistory->size() / 4);
        gpu.downloadBuffer(*mHistory, steps.data(), mHistory->size());
        const uint32_t iterations = mStepsPerSolve - 2;
        mStats.clear();
        double total = 0.0, last = 0.0;
        for (uint32_t s = 0; s < mSolves; ++s) {
            const float* first = &steps[size_t(s * mStepsPerSolve + 1) * (kStepBytes / 4)];
            uint32_t k = 0;
            double rel = 0.0;
            for (;; ++k) {
                const float* rec = first + size_t(k) * (kStepBytes / 4);
                rel = 0.0;
                for (int c = 0; c < 3; ++c)
                    rel = std::max(
                        rel, std::sqrt(double(rec[c]) / std::max(double(first[12 + c]), 1e-30)));
                uint32_t going;
                std::memcpy(&going, rec + 16, 4);
                if (k == iterations || !going) break;
            }
            total += k;
            last = rel;
        }
        mStats["iterations"] = total;
        mStats["relativeResidual"] = last;
    }
    std::map<std::string, double> stats() const override { return mStats; }

private:
    bool multigrid() const { return paramOr("linearSolver", "cg") == "multigrid"; }
    uint32_t solves() const {
        return paramOr("solver", "l2") == "l1" ? uint32_t(intOr("irlsIterations", 20)) : 1u;
    }
    uint32_t stepsPerSolve() const { return uint32_t(intOr("iterations", 50)) + 2; }
    // reflect() runs before the parameters exist (to declare them): defaults then.
    std::string paramOr(const std::string& name, const std::string& def) const {
        return params().count(name) ? param<std::string>(name) : def;
    }
    int intOr(const std::string& name, int def) const {
        return params().count(name) ? param<int>(name) : def;
    }
    static uint32_t u(uint64_t v) { return uint32_t(v); }

    KernelParams frame(const gpu::ComputePipeline& p) { return KernelParams(*this, p, *mCtx); }
    void barrier() { mCtx->cmd().barrier(); }
    void reduce(uint32_t slot, uint32_t gate, uint32_t solveSlot, uint32_t a, uint32_t b) {
        barrier();
        KernelParams k(*this, *mReduce, *mCtx);
        k.set("groups", mGroups)
            .set("slot", slot)
            .set("gateSlot", gate)
            .set("solveSlot", solveSlot)
            .set("fieldA", a)
            .set("fieldB", b)
            .set("levels", uint32_t(mLevels.size()));
        if (gate == kNoSlot)
            k.dispatchGroups(*mCtx, mBind, 1);
        else
            k.dispatchIndirect(*mCtx, mBind, *mArgs, 16 * kReduceArgs);
        barrier();
    }
    // x and r of one step: CG (x += alpha p, r -= alpha A p) or Jacobi (x += D^-1 r).
    void update(uint32_t slot, bool jacobi) {
        KernelParams(*this, *mUpdate, *mCtx)
            .set("slot", slot)
            .set("jacobi", jacobi ? 1u : 0u)
            .set("xOffset", u(mX))
            .set("rOffset", u(mR))
            .set("pOffset", u(mP))
            .set("qOffset", u(mQ))
            .dispatchIndirect(*mCtx, mBind, *mArgs, 0);
    }
    void residual(size_t l, uint64_t x, uint64_t b, uint64_t r, uint32_t slot) {
        KernelParams k(*this, *mResidual, *mCtx);
        k.setUints("levelSize", &mLevels[l].w, 2)
            .set("xOffset", u(x))
            .set("bOffset", u(b))
            .set("rOffset", u(r))
            .set("wOffset", u(mLevels[l].offset))
            .set("slot", slot);
        if (slot == kNoSlot)
            k.dispatch(*mCtx, mBind, mLevels[l].w, mLevels[l].h);
        else
            k.dispatchIndirect(*mCtx, mBind, *mArgs, 16 * l);
    }
    // One colour of a red-black sweep, or (residual) r = b - A x after a sweep that ended black.
    void smooth(size_t l, uint32_t colour, bool zeroGuess, uint32_t slot, bool residual = false) {
        KernelParams(*this, *mSmooth, *mCtx)
            .setUints("levelSize", &mLevels[l].w, 2)
            .set("xOffset", u(mMX + mLevels[l].offset))
            .set("bOffset", u(l == 0 ? mR : mMB + mLevels[l].offset))
            .set("wOffset", u(mLevels[l].offset))
            .set("colour", colour)
            .set("zeroGuess", zeroGuess ? 1u : 0u)
            .set("residual", residual ? 1u : 0u)
            .set("rOffset", u(mMR + mLevels[l].offset))
            .set("slot", slot)
            .dispatchIndirect(*mCtx, mBind, *mArgs, 16 * (kHalfArgs + l));
        barrier();
    }
    // z = M^-1 r by one V-cycle: (red, black)^nu before, (black, red)^nu after, so that M is
    // symmetric; the coarsest level gets kCoarsestSweeps symmetric sweeps.
    void vcycle(uint32_t slot) {
        const size_t last = mLevels.size() - 1;
        for (size_t l = 0; l < last; ++l) {
            for (uint32_t i = 0; i < mSweeps; ++i) {
                smooth(l, 0, i == 0, slot);
                smooth(l, 1, false, slot);
            }
            smooth(l, 0, false, slot, true);  // r = b - A x on the red half
            KernelParams(*this, *mRestrict, *mCtx)
                .setUints("fineSize", &mLevels[l].w, 2)
                .setUints("coarseSize", &mLevels[l + 1].w, 2)
                .set("rOffset", u(mMR + mLevels[l].offset))
                .set("bOffset", u(mMB + mLevels[l + 1].offset))
                .set("slot", slot)
                .dispatchIndirect(*mCtx, mBind, *mArgs, 16 * (l + 1));
            barrier();
        }
        for (uint32_t i = 0; i < kCoarsestSweeps; ++i) {
            smooth(last, 0, i == 0, slot);
            smooth(last, 1, false, slot);
        }
        for (uint32_t i = 0; i < kCoarsestSweeps; ++i) {
            smooth(last, 1, false, slot);
            smooth(last, 0, false, slot);
        }
        for (size_t l = last; l-- > 0;) {
            KernelParams(*this, *mProlong, *mCtx)
                .setUints("fineSize", &mLevels[l].w, 2)
                .setUints("coarseSize", &mLevels[l + 1].w, 2)
                .set("xOffset", u(mMX + mLevels[l].offset))
                .set("coarseOffset", u(mMX + mLevels[l + 1].offset))
                .set("slot", slot)
                .dispatchIndirect(*mCtx, mBind, *mArgs, 16 * l);
            barrier();
            for (uint32_t i = 0; i < mSweeps; ++i) {
                smooth(l, 1, false, slot);
                smooth(l, 0, false, slot);
            }
        }
    }

    std::shared_ptr<gpu::ComputePipeline> mWeights, mRhs, mScaleWeights, mResidual, mReduce,
        mDirection, mApply, mUpdate, mDot, mSmooth, mRestrict, mProlong, mCoarsen, mOutput, mPlot;
    ExecuteContext* mCtx = nullptr;
    gpu::Bindings mBind;
    std::shared_ptr<gpu::Buffer> mHistory, mArgs, mArgsFull;
    std::vector<uint32_t> mArgsUploaded;
    std::vector<Level> mLevels;
    uint64_t mN = 0, mX = 0, mB = 0, mR = 0, mP = 0, mQ = 0, mMX = 0, mMB = 0, mMR = 0;
    uint32_t mGroups = 0, mSolves = 1, mStepsPerSolve = 52, mSweeps = 1;
    std::map<std::string, double> mStats;
};

LOOM_REGISTER_PASS(PoissonReconstructPass, "PoissonReconstruct",
                   "screened Poisson reconstruction from a primal image and its gradients (L2: "
                   "CG, multigrid PCG or Jacobi; L1: IRLS)");

}  // namespace loom
