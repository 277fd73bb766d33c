// PoissonReconstruct against ground truth written independently of its kernels: a direct
// solve of the same screened Poisson problem by the discrete cosine transform (which
// diagonalises the Neumann Laplacian; the transform here is the plain O(n^2) cosine sum), the
// least-squares objective evaluated on the CPU, and exact inputs of a known image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <vector>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "tests/support/GpuSupport.h"

namespace loom {
namespace {

constexpr double kAlpha = 0.2;

// One colour channel of a W x H problem, row-major, double precision.
struct Channel {
    int w = 0, h = 0;
    std::vector<double> v;
    double& at(int x, int y) { return v[size_t(y) * w + x]; }
    double at(int x, int y) const { return v[size_t(y) * w + x]; }
};
Channel channel(const ImageData& img, int c) {
    Channel ch{int(img.width), int(img.height),
               std::vector<double>(size_t(img.width) * img.height)};
    for (size_t i = 0; i < ch.v.size(); ++i) ch.v[i] = img.pixels[i * 4 + c];
    return ch;
}

// Forward differences with the Neumann convention (last column / row: 0).
void forwardDifferences(const ImageData& x, ImageData& dx, ImageData& dy) {
    dx = ImageData::make(x.width, x.height, 4);
    dy = ImageData::make(x.width, x.height, 4);
    for (uint32_t y = 0; y < x.height; ++y)
        for (uint32_t i = 0; i < x.width; ++i)
            for (int c = 0; c < 3; ++c) {
                size_t p = (size_t(y) * x.width + i) * 4 + c;
                if (i + 1 < x.width) dx.pixels[p] = x.pixels[p + 4] - x.pixels[p];
                if (y + 1 < x.height)
                    dy.pixels[p] = x.pixels[p + size_t(x.width) * 4] - x.pixels[p];
            }
}

// b = alpha^2 f + D_x^T g_x + D_y^T g_y for uniform weights.
Channel rightHandSide(const Channel& f, const Channel& gx, const Channel& gy, double alpha) {
    Channel b = f;
    for (int y = 0; y < f.h; ++y)
        for (int x = 0; x < f.w; ++x) {
            double v = alpha * alpha * f.at(x, y);
            if (x + 1 < f.w) v -= gx.at(x, y);
            if (x > 0) v += gx.at(x - 1, y);
            if (y + 1 < f.h) v -= gy.at(x, y);
            if (y > 0) v += gy.at(x, y - 1);
            b.at(x, y) = v;
        }
    return b;
}

// DCT-II along one axis: X_k = sum_n x_n cos(pi k (n + 1/2) / N); its inverse is
// x_n = X_0 / N + 2/N sum_{k>0} X_k cos(pi k (n + 1/2) / N).
void dct(Channel& c, bool alongX, bool inverse) {
    const int n = alongX ? c.w : c.h, lines = alongX ? c.h : c.w;
    std::vector<double> in(n), out(n);
    for (int l = 0; l < lines; ++l) {
        for (int i = 0; i < n; ++i) in[i] = alongX ? c.at(i, l) : c.at(l, i);
        for (int k = 0; k < n; ++k) {
            double s = 0.0;
            for (int i = 0; i < n; ++i) {
                if (!inverse)
                    s += in[i] * std::cos(std::numbers::pi * k * (i + 0.5) / n);
                else
                    s += in[i] * std::cos(std::numbers::pi * i * (k + 0.5) / n) *
                         (i == 0 ? 1.0 : 2.0);
            }
            out[k] = inverse ? s / n : s;
        }
        for (int i = 0; i < n; ++i) (alongX ? c.at(i, l) : c.at(l, i)) = out[i];
    }
}

// The exact minimiser of ||alpha (x - f)||^2 + ||D_x x - g_x||^2 + ||D_y x - g_y||^2: the
// cosine basis diagonalises alpha^2 I + L with eigenvalues alpha^2 + (2 - 2 cos(pi k / W)) +
// (2 - 2 cos(pi l / H)).
Channel directSolve(const Channel& f, const Channel& gx, const Channel& gy, double alpha) {
    Channel b = rightHandSide(f, gx, gy, alpha);
    dct(b, true, false);
    dct(b, false, false);
    for (int l = 0; l < b.h; ++l)
        for (int k = 0; k < b.w; ++k)
            b.at(k, l) /= alpha * alpha + (2 - 2 * std::cos(std::numbers::pi * k / b.w)) +
                          (2 - 2 * std::cos(std::numbers::pi * l / b.h));
    dct(b, false, true);
    dct(b, true, true);
    return b;
}

// The rows of P x - [alpha f; g_x; g_y] at one pixel for all channels: their Euclidean norms
// over RGB are what L1 sums and what IRLS weighs by.
struct Objective {
    double l2 = 0.0;  // sum of squares over every row and channel
    double l1 = 0.0;  // sum over rows of ||row||_RGB
};
Objective objective(const ImageData& x, const ImageData& f, const ImageData& gx,
                    const ImageData& gy, double alpha) {
    Objective o;
    const uint32_t w = x.width, h = x.height;
    auto px = [&](const ImageData& img, uint32_t i, uint32_t y, int c) {
        return double(img.pixels[(size_t(y) * w + i) * 4 + c]);
    };
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t i = 0; i < w; ++i) {
            double ep = 0, ex = 0, ey = 0;
            for (int c = 0; c < 3; ++c) {
                double e = alpha * (px(x, i, y, c) - px(f, i, y, c));
                ep += e * e;
                if (i + 1 < w) {
                    e = px(x, i + 1, y, c) - px(x, i, y, c) - px(gx, i, y, c);
                    ex += e * e;
                }
                if (y + 1 < h) {
                    e = px(x, i, y + 1, c) - px(x, i, y, c) - px(gy, i, y, c);
                    ey += e * e;
                }
            }
            o.l2 += ep + ex + ey;
            o.l1 += std::sqrt(ep) + std::sqrt(ex) + std::sqrt(ey);
        }
    return o;
}

// A smooth image with edges and an HDR highlight, in every channel differently.
ImageData knownImage(uint32_t w, uint32_t h) {
    ImageData img = ImageData::make(w, h, 4);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            for (int c = 0; c < 4; ++c) {
                double u = double(x) / w, v = double(y) / h;
                double val = 0.5 + 0.3 * std::sin(6.0 * u + c) * std::cos(4.0 * v - c);
                if (u > 0.6 && v < 0.4) val += 0.8;                             // an edge
                if (std::hypot(u - 0.3, v - 0.7) < 0.08) val += 4.0 * (c + 1);  // a highlight
                img.pixels[(size_t(y) * w + x) * 4 + c] = c == 3 ? 1.0f : float(val);
            }
    return img;
}

ImageData noisy(const ImageData& img, double sigma, uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, sigma);
    ImageData out = img;
    for (size_t i = 0; i < out.pixels.size(); ++i)
        if (i % 4 != 3) out.pixels[i] += float(n(rng));
    return out;
}

// A known image, its exact forward differences, and noisy versions of all three.
struct Problem {
    ImageData truth, f, dx, dy;
};
Problem noisyProblem(uint32_t w, uint32_t h, double sigmaPrimal, double sigmaGradient,
                     uint32_t seed) {
    Problem p;
    p.truth = knownImage(w, h);
    forwardDifferences(p.truth, p.dx, p.dy);
    p.f = noisy(p.truth, sigmaPrimal, seed);
    p.dx = noisy(p.dx, sigmaGradient, seed + 1);
    p.dy = noisy(p.dy, sigmaGradient, seed + 2);
    return p;
}

struct Solve {
    ImageData image;
    std::vector<float> history;  // PoissonStep records, 20 floats each
    std::map<std::string, double> stats;
};

class Reconstruction {
public:
    Reconstruction(const ImageData& primal, const ImageData& dx, const ImageData& dy)
        : mDir("loom-poisson") {
        writeImage(mDir / "primal.exr", primal);
        writeImage(mDir / "dx.exr", dx);
        writeImage(mDir / "dy.exr", dy);
        auto graph = RenderGraph::parse(R"({"passes": [
            {"name": "f", "type": "ImageLoader", "params": {"path": "primal.exr"}},
            {"name": "gx", "type": "ImageLoader", "params": {"path": "dx.exr"}},
            {"name": "gy", "type": "ImageLoader", "params": {"path": "dy.exr"}},
            {"name": "poisson", "type": "PoissonReconstruct"}],
          "edges": [["f.output", "poisson.primal"], ["gx.output", "poisson.dx"],
                    ["gy.output", "poisson.dy"]],
          "outputs": ["poisson.output", "poisson.history", "poisson.residualPlot"]})",
                                        mDir / "poisson.json");
        mRenderer = std::make_unique<Renderer>(test::gpuContext(), std::move(graph), primal.width,
                                               primal.height);
    }
    Solve run(const std::map<std::string, json>& params) {
        for (const auto& [k, v] : params) mRenderer->graph().setParam("poisson." + k, v);
        mRenderer->frame();
        Solve s;
        s.image = mRenderer->readOutput("poisson.output");
        auto buf = mRenderer->graph().outputBuffer("poisson.history");
        s.history.resize(buf->size() / 4);
        test::gpuContext()->downloadBuffer(*buf, s.history.data(), buf->size());
        s.stats = mRenderer->graph().findPass("poisson")->stats();
        return s;
    }

private:
    test::TempDir mDir;
    std::unique_ptr<Renderer> mRenderer;
};

// Largest |a - b| / max(|b|) over RGB.
double maxRelativeError(const ImageData& a, const ImageData& b) {
    double worst = 0.0, scale = 0.0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        if (i % 4 == 3) continue;
        worst = std::max(worst, std::abs(double(a.pixels[i]) - double(b.pixels[i])));
        scale = std::max(scale, std::abs(double(b.pixels[i])));
    }
    return worst / scale;
}

ImageData fromChannels(const Channel (&c)[3]) {
    ImageData img = ImageData::make(uint32_t(c[0].w), uint32_t(c[0].h), 4);
    for (size_t i = 0; i < c[0].v.size(); ++i) {
        for (int k = 0; k < 3; ++k) img.pixels[i * 4 + k] = float(c[k].v[i]);
        img.pixels[i * 4 + 3] = 1.0f;
    }
    return img;
}

ImageData directSolve(const ImageData& f, const ImageData& gx, const ImageData& gy) {
    Channel out[3];
    for (int c = 0; c < 3; ++c)
        out[c] = directSolve(channel(f, c), channel(gx, c), channel(gy, c), kAlpha);
    return fromChannels(out);
}

TEST(PoissonReconstruct, DirectDctSolveIsTheMinimiser) {
    // The ground truth itself: its solution has a zero gradient of the objective, i.e. any
    // perturbation raises the objective (checked along random directions).
    const uint32_t w = 13, h = 9;
    ImageData f = noisy(knownImage(w, h), 0.3, 1), gx = noisy(f, 0.5, 2), gy = noisy(f, 0.5, 3);
    ImageData x = directSolve(f, gx, gy);
    double best = objective(x, f, gx, gy, kAlpha).l2;
    std::mt19937 rng(7);
    std::normal_distribution<float> n(0.0f, 1e-2f);
    for (int t = 0; t < 8; ++t) {
        ImageData y = x;
        for (auto& v : y.pixels) v += n(rng);
        EXPECT_GT(objective(y, f, gx, gy, kAlpha).l2, best);
    }
}

TEST(PoissonReconstruct, L2MatchesTheDirectDctSolve) {
    // Odd, non-square size; noisy primal and gradients inconsistent with each other.
    const uint32_t w = 37, h = 23;
    auto [truth, f, dx, dy] = noisyProblem(w, h, 0.2, 0.1, 11);
    ImageData exact = directSolve(f, dx, dy);
    Reconstruction rec(f, dx, dy);
    for (std::string solver : {"cg", "multigrid"}) {
        Solve s = rec.run({{"linearSolver", solver}, {"iterations", solver == "cg" ? 300 : 40}});
        double err = maxRelativeError(s.image, exact);
        EXPECT_LT(err, 1e-4) << solver;
        EXPECT_LT(s.stats.at("relativeResidual"), 1e-5) << solver;
        std::printf("[ l2 %s ] %g steps, relative residual %.3g, max error vs DCT %.3g\n",
                    solver.c_str(), s.stats.at("iterations"), s.stats.at("relativeResidual"), err);
    }
    // Jacobi converges too, slowly (alpha^2 = 0.04 leaves low frequencies almost undamped).
    double previous = INFINITY;
    for (int it : {10, 100, 1000}) {
        Solve s = rec.run({{"linearSolver", "jacobi"}, {"iterations", it}});
        double err = maxRelativeError(s.image, exact);
        EXPECT_LT(err, previous) << "jacobi " << it;
        previous = err;
        std::printf("[ l2 jacobi ] %d steps, max error vs DCT %.3g\n", it, err);
    }
}

TEST(PoissonReconstruct, ExactInputsRecoverTheImage) {
    // b = P x* exactly: x* is the minimiser under every weighting, so L2 and L1 (whose weights
    // change every solve) must both stay at it although the solve starts from the primal and
    // runs 50 steps per solve; a sign or boundary slip in the right-hand side moves it away.
    const uint32_t w = 40, h = 27;
    ImageData truth = knownImage(w, h), dx, dy;
    forwardDifferences(truth, dx, dy);
    Reconstruction rec(truth, dx, dy);
    for (std::string solver : {"l2", "l1"})
        for (std::string linear : {"cg", "multigrid"}) {
            Solve s = rec.run({{"solver", solver},
                               {"linearSolver", linear},
                               {"iterations", 50},
                               {"irlsIterations", 8}});
            EXPECT_LT(maxRelativeError(s.image, truth), 1e-4) << solver << " " << linear;
        }
}

TEST(PoissonReconstruct, ExactGradientsFixTheImageUpToThePrimalsMean) {
    // With exact gradients and a primal off by noise plus a constant, the minimiser is x* plus
    // (alpha^2 I + L)^-1 alpha^2 (noise + constant): the constant survives exactly (L kills
    // constants), the noise is low-passed. Checked against the DCT solve, at equal mean.
    const uint32_t w = 32, h = 32;
    ImageData truth = knownImage(w, h), dx, dy;
    forwardDifferences(truth, dx, dy);
    ImageData f = noisy(truth, 0.0, 0);
    for (size_t i = 0; i < f.pixels.size(); ++i)
        if (i % 4 != 3) f.pixels[i] += 0.25f;
    Reconstruction rec(f, dx, dy);
    Solve s = rec.run({{"linearSolver", "multigrid"}, {"iterations", 30}});
    ImageData shifted = truth;
    for (size_t i = 0; i < shifted.pixels.size(); ++i)
        if (i % 4 != 3) shifted.pixels[i] += 0.25f;
    EXPECT_LT(maxRelativeError(s.image, shifted), 1e-4);
}

TEST(PoissonReconstruct, CgDecreasesTheObjectiveAndTheResidualEveryStep) {
    const uint32_t w = 29, h = 31;
    auto [truth, f, dx, dy] = noisyProblem(w, h, 0.3, 0.2, 21);
    Reconstruction rec(f, dx, dy);
    for (std::string linear : {"cg", "multigrid"}) {
        // Multigrid reaches float precision after ~8 steps; compare before it does.
        const int n = linear == "cg" ? 12 : 6;
        double previous = INFINITY;
        Solve last;
        for (int it = 1; it <= n; ++it) {
            // The objective of each output, on the CPU: CG minimises it over growing Krylov
            // spaces, so it can only fall.
            last = rec.run({{"linearSolver", linear}, {"iterations", it}});
            double o = objective(last.image, f, dx, dy, kAlpha).l2;
            EXPECT_LT(o, previous) << linear << " step " << it;
            previous = o;
        }
        // The recorded residual history of the n-step solve: r.r per step, every channel
        // falling, and the last one equal to the residual of the output computed here.
        const float* rec0 = &last.history[20];  // solve 0, step 0 (after the weights record)
        for (int k = 1; k <= n; ++k)
            for (int c = 0; c < 3; ++c)
                EXPECT_LT(rec0[k * 20 + c], rec0[(k - 1) * 20 + c])
                    << linear << " step " << k << " channel " << c;
        for (int c = 0; c < 3; ++c) {
            Channel x = channel(last.image, c),
                    b = rightHandSide(channel(f, c), channel(dx, c), channel(dy, c), kAlpha);
            double rr = 0.0, bb = 0.0;
            for (int y = 0; y < int(h); ++y)
                for (int i = 0; i < int(w); ++i) {
                    double ax = (kAlpha * kAlpha) * x.at(i, y);
                    if (i + 1 < int(w)) ax += x.at(i, y) - x.at(i + 1, y);
                    if (i > 0) ax += x.at(i, y) - x.at(i - 1, y);
                    if (y + 1 < int(h)) ax += x.at(i, y) - x.at(i, y + 1);
                    if (y > 0) ax += x.at(i, y) - x.at(i, y - 1);
                    double r = b.at(i, y) - ax;
                    rr += r * r;
                    bb += b.at(i, y) * b.at(i, y);
                }
            EXPECT_NEAR(std::sqrt(rec0[n * 20 + c]), std::sqrt(rr), 1e-3 * std::sqrt(bb))
                << linear << " channel " << c;
            EXPECT_NEAR(rec0[12 + c], bb, 1e-4 * bb) << "b.b channel " << c;
        }
    }
}

TEST(PoissonReconstruct, MultigridNeedsFarFewerStepsThanCg) {
    const uint32_t w = 64, h = 48;
    auto [truth, f, dx, dy] = noisyProblem(w, h, 0.2, 0.1, 31);
    Reconstruction rec(f, dx, dy);
    double steps[2];
    int i = 0;
    for (std::string linear : {"cg", "multigrid"}) {
        Solve s = rec.run({{"linearSolver", linear}, {"iterations", 500}, {"tolerance", 1e-4}});
        EXPECT_LT(s.stats.at("relativeResidual"), 1e-4) << linear;
        steps[i++] = s.stats.at("iterations");
        std::printf("[ %s ] %g steps to 1e-4\n", linear.c_str(), s.stats.at("iterations"));
    }
    EXPECT_LT(steps[1] * 3, steps[0]);
}

TEST(PoissonReconstruct, L1LowersTheL1ObjectiveAndResistsOutliers) {
    // IRLS minimises the sum of the rows' RGB norms: its result must score lower on that sum
    // than the L2 solution, and sparse gross gradient errors (outliers) must disturb it less.
    const uint32_t w = 32, h = 24;
    ImageData truth = knownImage(w, h), dx, dy;
    forwardDifferences(truth, dx, dy);
    std::mt19937 rng(41);
    for (int k = 0; k < 20; ++k) {
        size_t p = rng() % (size_t(w) * h);
        for (int c = 0; c < 3; ++c) dx.pixels[p * 4 + c] += 3.0f;
    }
    ImageData f = noisy(truth, 0.05, 42);
    Reconstruction rec(f, dx, dy);
    Solve l2 = rec.run({{"solver", "l2"}, {"linearSolver", "multigrid"}, {"iterations", 40}});
    Solve l1 = rec.run({{"solver", "l1"},
                        {"linearSolver", "multigrid"},
                        {"iterations", 40},
                        {"irlsIterations", 20}});
    Objective o2 = objective(l2.image, f, dx, dy, kAlpha),
              o1 = objective(l1.image, f, dx, dy, kAlpha);
    EXPECT_LT(o1.l1, o2.l1);
    EXPECT_GT(o1.l2, o2.l2);  // and L2 is the least-squares optimum
    double e1 = maxRelativeError(l1.image, truth), e2 = maxRelativeError(l2.image, truth);
    std::printf("[ outliers ] L1 objective l1 %.4g l2 %.4g; max error vs truth l1 %.3g l2 %.3g\n",
                o1.l1, o2.l1, e1, e2);
    EXPECT_LT(e1, 0.5 * e2);
}

TEST(PoissonReconstruct, SameInputsSameBytes) {
    const uint32_t w = 20, h = 12;
    ImageData f = noisy(knownImage(w, h), 0.2, 51), dx = noisy(f, 0.3, 52), dy = noisy(f, 0.3, 53);
    Reconstruction rec(f, dx, dy);
    for (std::string linear : {"cg", "multigrid"}) {
        Solve a = rec.run({{"solver", "l1"}, {"linearSolver", linear}, {"irlsIterations", 3}});
        Solve b = rec.run({});
        EXPECT_EQ(
            0, std::memcmp(a.image.pixels.data(), b.image.pixels.data(), a.image.pixels.size() * 4))
            << linear;
    }
}

TEST(PoissonReconstruct, SolversSwitchFromLuaWithoutRecompiling) {
    // graphs/poisson_pt.json driven by a Lua script: every solver and both norms in one
    // renderer, parameters set between frames, images captured.
    test::TempDir dir("loom-poisson-lua");
    const std::string src = LOOM_SOURCE_DIR;
    {
        std::ofstream lua(dir / "solvers.lua");
        lua << "local r = loom.renderer{graph = '" << src << "/graphs/poisson_pt.json', scene = '"
            << src << "/scenes/cornell_box.json', width = 24, height = 16}\n"
            << R"(r:frame()
for _, s in ipairs{'cg', 'multigrid', 'jacobi'} do
  r:set('poisson.linearSolver', s)
  r:set('poisson.iterations', 400)
  r:set('poisson.tolerance', 1e-3)
  -- Ports changed (scratch sizes): the graph restarts its accumulation, and on its first
  -- frame the mean is the primal itself, whose gradients the primal satisfies exactly.
  r:frame()
  r:frame()
  local st = r:stats()
  print(string.format('%s %d %.3g', s, st['poisson.iterations'], st['poisson.relativeResidual']))
end
r:set('poisson.solver', 'l1')
r:set('poisson.linearSolver', 'multigrid')
r:set('poisson.iterations', 10)
r:set('poisson.irlsIterations', 4)
r:frame()
r:frame()
print(string.format('l1 %d', r:stats()['poisson.iterations']))
r:capture('poisson.output', 'l1.exr')
r:capture('poisson.residualPlot', 'plot.png')
)";
    }
    std::string cmd = "cd '" + dir.str() + "' && LOOM_PROGRESS=0 '" + LOOM_BINARY +
                      "' run solvers.lua > out.txt 2> err.txt";
    int status = std::system(cmd.c_str());
    auto read = [&](const char* f) {
        std::ifstream in(dir / f);
        std::stringstream ss;
        ss << in.rdbuf();
        return ss.str();
    };
    ASSERT_EQ(status, 0) << read("err.txt");
    std::istringstream out(read("out.txt"));
    std::string name;
    double steps = 0, residual = 0;
    for (std::string expect : {"cg", "multigrid", "jacobi"}) {
        ASSERT_TRUE(out >> name >> steps >> residual) << read("out.txt");
        EXPECT_EQ(name, expect);
        EXPECT_GT(steps, 0);
        // Jacobi stops at 400 steps short of 1e-3 (2.6e-3 measured): it is the slow one.
        EXPECT_LT(residual, name == "jacobi" ? 1e-2 : 1e-3) << name;
    }
    ASSERT_TRUE(out >> name >> steps);
    EXPECT_EQ(name, "l1");
    EXPECT_GT(steps, 4);  // 4 solves, each at least one step
    ImageData l1 = readImage(dir / "l1.exr");
    EXPECT_EQ(l1.width, 24u);
    EXPECT_EQ(readImage(dir / "plot.png").width, 256u);
}

TEST(PoissonReconstruct, InputOfAnotherSizeIsAUserError) {
    test::TempDir dir("loom-poisson");
    writeImage(dir / "a.exr", knownImage(8, 8));
    writeImage(dir / "b.exr", knownImage(8, 6));
    auto graph = RenderGraph::parse(R"({"passes": [
        {"name": "a", "type": "ImageLoader", "params": {"path": "a.exr"}},
        {"name": "b", "type": "ImageLoader", "params": {"path": "b.exr"}},
        {"name": "poisson", "type": "PoissonReconstruct"}],
      "edges": [["a.output", "poisson.primal"], ["a.output", "poisson.dx"],
                ["b.output", "poisson.dy"]],
      "outputs": ["poisson.output"]})",
                                    dir / "g.json");
    Renderer r(test::gpuContext(), std::move(graph), 8, 8);
    try {
        r.frame();
        FAIL() << "no error";
    } catch (const UserError& e) {
        EXPECT_NE(std::string(e.what()).find("input 'dy' is 8x6 but the frame is 8x8"),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace loom
