// Specular constraints of manifold walks (shaders/lib/manifold/constraints.glsl) against
// configurations built here in double precision with Snell's law and the mirror law: C = 0 on
// the manifold, |C| grows like the angle w_o is turned away from it, the phi difference wraps,
// and total internal reflection is handled as the reference code does.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "tests/support/GpuSupport.h"

namespace loom {
namespace {

struct V {
    double x, y, z;
};
V operator+(V a, V b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
V operator*(double s, V a) {
    return {s * a.x, s * a.y, s * a.z};
}
double dot(V a, V b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
V cross(V a, V b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
V normalize(V a) {
    return (1.0 / std::sqrt(dot(a, a))) * a;
}

// Snell's law in vector form (w and the result point away from the surface); eta = n_int/n_ext
// with n towards the exterior. Returns false under total internal reflection.
bool refract(V w, V n, double eta, V& out) {
    double c = dot(w, n);
    double e = c >= 0 ? eta : 1.0 / eta;  // n_t / n_i
    V m = c >= 0 ? n : -1.0 * n;
    double ci = std::abs(c), s2t = (1 - ci * ci) / (e * e);
    if (s2t >= 1) return false;
    double ct = std::sqrt(1 - s2t);
    out = normalize((-1.0 / e) * w + (ci / e - ct) * m);
    return true;
}
V reflect(V w, V n) {
    return (2 * dot(w, n)) * n + -1.0 * w;
}

struct Config {
    V wi, n, wo;
    double eta = 1.5;
    bool reflection = false;
    double a = 0, b = 0;  // wrap test angles
};

struct Result {
    double cx, cy;
    bool valid;
    double half;
    double wrapped;
};

std::vector<Result> evaluate(const std::vector<Config>& cs) {
    test::TempDir dir("loom-manifold");
    uint32_t w = uint32_t(cs.size());
    ImageData in = ImageData::make(w, 4, 4);
    for (uint32_t x = 0; x < w; ++x) {
        const Config& c = cs[x];
        float row[4][4] = {{float(c.wi.x), float(c.wi.y), float(c.wi.z), 0},
                           {float(c.n.x), float(c.n.y), float(c.n.z), float(c.eta)},
                           {float(c.wo.x), float(c.wo.y), float(c.wo.z), c.reflection ? 1.f : 0.f},
                           {float(c.a), float(c.b), 0, 0}};
        for (uint32_t y = 0; y < 4; ++y)
            for (uint32_t k = 0; k < 4; ++k) in.at(x, y, k) = row[y][k];
    }
    writeImage(dir / "in.exr", in);
    auto graph = RenderGraph::parse(
        R"({"passes": [{"name": "in", "type": "ImageLoader", "params": {"path": "in.exr"}},
        {"name": "k", "type": "ComputePass", "params": {"shader": ")" +
            std::string(LOOM_TEST_DATA) + R"(/manifold_constraints.comp",
          "inputs": {"input": {"glsl": "inputImage", "format": "rgba32f"}},
          "outputs": {"output": {"glsl": "outputImage"}}}}],
        "edges": [["in.output", "k.input"]], "outputs": ["k.output"]})",
        dir / "graph.json");
    Renderer r(test::gpuContext(), std::move(graph), w, 4);
    r.frame();
    ImageData out = r.readOutput("k.output");
    std::vector<Result> res;
    for (uint32_t x = 0; x < w; ++x)
        res.push_back({out.at(x, 0, 0), out.at(x, 0, 1), out.at(x, 0, 2) != 0.0f, out.at(x, 0, 3),
                       out.at(x, 1, 0)});
    return res;
}

V randomDir(std::mt19937& rng) {
    std::normal_distribution<double> g;
    return normalize({g(rng), g(rng), g(rng)});
}

// Random exact configurations: reflection, refraction from outside and from inside (no TIR).
std::vector<Config> exactConfigs(int count, uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<Config> cs;
    while (int(cs.size()) < count) {
        Config c;
        c.n = randomDir(rng);
        c.wi = randomDir(rng);
        c.reflection = cs.size() % 3 == 0;
        if (c.reflection) {
            if (dot(c.wi, c.n) < 0) c.n = -1.0 * c.n;
            c.wo = reflect(c.wi, c.n);
        } else if (!refract(c.wi, c.n, c.eta, c.wo)) {
            continue;
        }
        if (std::abs(dot(c.wi, c.n)) < 0.05) continue;  // grazing: ill-conditioned angles
        cs.push_back(c);
    }
    return cs;
}

TEST(ManifoldConstraints, ZeroOnTheSpecularManifold) {
    auto cs = exactConfigs(256, 7);
    auto res = evaluate(cs);
    double worst = 0, worstHalf = 0;
    for (size_t i = 0; i < cs.size(); ++i) {
        ASSERT_TRUE(res[i].valid) << i;
        worst = std::max(worst, std::hypot(res[i].cx, res[i].cy));
        worstHalf = std::max(worstHalf, res[i].half);
    }
    // Float evaluation of directions built in double: a few ulps of angle.
    EXPECT_LT(worst, 2e-5) << "angle-difference constraint off the exact configurations";
    EXPECT_LT(worstHalf, 2e-5) << "half-vector constraint off the exact configurations";
    std::printf("exact configurations: max |C_angle| %.3g, max |C_half| %.3g\n", worst, worstHalf);
}

TEST(ManifoldConstraints, GrowsLikeTheAngleOffTheManifold) {
    // Turning w_o by delta away from the solution moves (theta, phi) by delta in the metric
    // dtheta^2 + sin^2(theta) dphi^2; the frame keeps sin(theta) >= sqrt(2/3), so
    // delta <= |C| <= delta / sqrt(2/3) to first order. An unwrapped phi difference at the
    // frame's seam, or a frame with its pole near w_o, breaks the upper bound.
    auto cs = exactConfigs(512, 11);
    std::mt19937 rng(3);
    const double delta = 2e-3;
    for (auto& c : cs) {
        V axis = normalize(cross(c.wo, randomDir(rng)));
        c.wo = normalize(std::cos(delta) * c.wo + std::sin(delta) * cross(axis, c.wo));
    }
    // w_o around a full circle in the xz plane (the frame's pole is then y), turned by delta
    // about y: phi sweeps every value, and steps finer than delta put some solutions and their
    // perturbed w_o on both sides of the frame's phi seam.
    const int sweep = 4096;
    for (int i = 0; i < sweep; ++i) {
        double a = 2 * 3.14159265358979 * (i + 0.5) / sweep;
        Config c;
        c.reflection = true;
        c.wo = {std::cos(a), 0, std::sin(a)};
        c.wi = randomDir(rng);
        if (dot(c.wi, c.wo) < -0.5) c.wi = -1.0 * c.wi;
        c.n = normalize(c.wi + c.wo);
        c.wo = {std::cos(a + delta), 0, std::sin(a + delta)};
        cs.push_back(c);
    }
    auto res = evaluate(cs);
    double lo = 1e9, hi = 0;
    for (size_t i = 0; i < cs.size(); ++i) {
        double r = std::hypot(res[i].cx, res[i].cy) / delta;
        lo = std::min(lo, r);
        hi = std::max(hi, r);
        EXPECT_GT(res[i].half, 0.1 * delta) << i;
    }
    EXPECT_GT(lo, 0.98);
    EXPECT_LT(hi, 1.0 / std::sqrt(2.0 / 3.0) + 0.02);
    std::printf("|C| / delta in [%.4f, %.4f] (bounds 1, %.4f)\n", lo, hi, 1 / std::sqrt(2.0 / 3));
}

TEST(ManifoldConstraints, PhiDifferenceWrapsIntoMinusPiPi) {
    std::vector<Config> cs;
    const double pi = 3.14159265358979;
    double pairs[][2] = {
        {pi - 0.01, -pi + 0.01}, {-pi + 0.02, pi - 0.03}, {0.5, 0.25}, {3.0, -3.0}, {-2.0, 2.5},
        {pi - 1e-3, pi - 1e-3}};
    for (auto& p : pairs) {
        Config c = exactConfigs(1, 1)[0];
        c.a = p[0];
        c.b = p[1];
        cs.push_back(c);
    }
    auto res = evaluate(cs);
    for (size_t i = 0; i < cs.size(); ++i) {
        double d = cs[i].a - cs[i].b;
        double expected = d - 2 * pi * std::floor((d + pi) / (2 * pi));
        EXPECT_NEAR(res[i].wrapped, expected, 1e-5) << cs[i].a << " - " << cs[i].b;
        EXPECT_LE(std::abs(res[i].wrapped), pi + 1e-5);
    }
}

TEST(ManifoldConstraints, TotalInternalReflectionSwapsTheRoles) {
    // From inside glass beyond the critical angle w_i does not refract: the constraint refracts
    // w_o instead and compares it with w_i (valid, and zero when w_i is w_o's refraction).
    std::vector<Config> cs;
    V n{0, 0, 1};
    double eta = 1.5;
    double crit = std::asin(1 / eta);
    // w_i inside (z < 0) beyond the critical angle; w_o outside.
    Config c;
    c.n = n;
    c.eta = eta;
    c.wi = normalize({std::sin(crit + 0.2), 0, -std::cos(crit + 0.2)});
    c.wo = normalize({-0.3, 0.1, 0.9});
    cs.push_back(c);
    // The swapped roles on the manifold: w_i is exactly the refraction of w_o (w_i beyond TIR
    // is impossible then, so take w_i inside within the critical angle from the outside w_o).
    Config d = c;
    ASSERT_TRUE(refract(d.wo, n, eta, d.wi));
    cs.push_back(d);
    // Both inside beyond the critical angle: on no refraction manifold.
    Config e = c;
    e.wo = normalize({-std::sin(crit + 0.3), 0, -std::cos(crit + 0.3)});
    cs.push_back(e);
    auto res = evaluate(cs);
    EXPECT_TRUE(res[0].valid);
    EXPECT_GT(std::hypot(res[0].cx, res[0].cy), 0.1);
    EXPECT_TRUE(res[1].valid);
    EXPECT_LT(std::hypot(res[1].cx, res[1].cy), 2e-5);
    EXPECT_FALSE(res[2].valid);
}

// ---------------------------------------------------------------------------------------------
// Derivatives against central finite differences of the constraint value itself.

ImageData runKernel(const std::string& kernel, const ImageData& in) {
    test::TempDir dir("loom-manifold");
    writeImage(dir / "in.exr", in);
    auto graph = RenderGraph::parse(
        R"({"passes": [{"name": "in", "type": "ImageLoader", "params": {"path": "in.exr"}},
        {"name": "k", "type": "ComputePass", "params": {"shader": ")" +
            std::string(LOOM_TEST_DATA) + "/" + kernel + R"(",
          "inputs": {"input": {"glsl": "inputImage", "format": "rgba32f"}},
          "outputs": {"output": {"glsl": "outputImage"}}}}],
        "edges": [["in.output", "k.input"]], "outputs": ["k.output"]})",
        dir / "graph.json");
    Renderer r(test::gpuContext(), std::move(graph), in.width, in.height);
    r.frame();
    return r.readOutput("k.output");
}

// A vertex on a sphere (centre c, radius R, outward normal) moved along the great circle of
// tangent t by arc length e: x(e) = c + R (cos(e/R) r + sin(e/R) t), n(e) = (x(e) - c) / R, so
// dx/de = t and dn/de = t / R at e = 0. The neighbours move linearly along their own vectors.
struct Chain {
    V c;
    double R;
    V r, t;  // unit radial direction and unit tangent at the vertex
    V prev, next, dprev, dnext;
    double eta;
    bool reflection;
    V frameDir;
    double wx = 1, wn = 1;  // weights of the vertex's and neighbours' motion
};

void fill(ImageData& img, uint32_t x, const Chain& ch, double e, double scale) {
    double a = e * ch.wx / ch.R;
    V rad = std::cos(a) * ch.r + std::sin(a) * ch.t;
    V xv = ch.c + ch.R * rad;
    V xp = ch.prev + (e * ch.wn) * ch.dprev, xn = ch.next + (e * ch.wn) * ch.dnext;
    V rows[9] = {xp,
                 xv,
                 xn,
                 rad,
                 (scale * ch.wn) * ch.dprev,
                 (scale * ch.wx) * ch.t,
                 (scale * ch.wx / ch.R) * ch.t,
                 (scale * ch.wn) * ch.dnext,
                 ch.frameDir};
    for (uint32_t y = 0; y < 9; ++y) {
        img.at(x, y, 0) = float(rows[y].x);
        img.at(x, y, 1) = float(rows[y].y);
        img.at(x, y, 2) = float(rows[y].z);
        img.at(x, y, 3) = 0.0f;
    }
    img.at(x, 1, 3) = float(ch.eta);
    img.at(x, 2, 3) = ch.reflection ? 1.0f : 0.0f;
}

// Columns per configuration i: 5i = C at -h, 5i+1 at +h, 5i+2 at -h/2, 5i+3 at +h/2, and
// 5i+4 the analytic derivative (row 1) at 0; row 0 holds C. The truncation error of the h/2
// difference is measured as its distance to the h difference (Richardson), plus the
// evaluation error of C (float, and lavapipe's atan approximation: ~1e-6) over h/2.
void expectDerivativesMatch(const ImageData& out, uint32_t n, double h, const char* what) {
    double worst = 0, worstAbs = 0;
    int bad = 0;
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 2; ++k) {
            double fdH = (double(out.at(5 * i + 1, 0, k)) - out.at(5 * i, 0, k)) / (2 * h);
            double fd = (double(out.at(5 * i + 3, 0, k)) - out.at(5 * i + 2, 0, k)) / h;
            double an = out.at(5 * i + 4, 1, k);
            double tol = std::abs(fdH - fd) + 1e-6 / (h / 2) + 1e-4 * std::abs(an);
            worst = std::max(worst, std::abs(fd - an) / tol);
            worstAbs = std::max(worstAbs, std::abs(fd - an));
            if (std::abs(fd - an) > tol && bad++ < 5)
                ADD_FAILURE() << what << ", config " << i << " component " << k << ": analytic "
                              << an << " fd " << fd << " (fd at 2h " << fdH << ")";
        }
    EXPECT_EQ(bad, 0) << what;
    std::printf("%s: worst |fd - analytic| %.3g, / tol %.3f, %u configs\n", what, worstAbs, worst,
                n);
}

TEST(ManifoldConstraints, AngleDifferenceDerivativeMatchesFiniteDifferences) {
    // Configurations near the manifold (the Newton walk's regime) and away from it, for
    // reflection and refraction from both sides, moving the vertex (with its normal), its
    // neighbours, or all together. Each column block: the point at -h, at +h, and the analytic
    // derivative at 0 (position columns hold x(+-h), the derivative column x(0)).
    std::mt19937 rng(5);
    std::vector<Chain> chains;
    while (chains.size() < 192) {
        Chain ch;
        ch.c = {0.2, -0.1, 0.3};
        ch.R = 0.8;
        ch.r = randomDir(rng);
        ch.t = normalize(cross(ch.r, randomDir(rng)));
        V x = ch.c + ch.R * ch.r;
        V wi = randomDir(rng);
        ch.reflection = chains.size() % 2 == 0;
        ch.eta = 1.5;
        V wo;
        if (ch.reflection) {
            if (dot(wi, ch.r) < 0.1) continue;
            wo = reflect(wi, ch.r);
        } else if (!refract(wi, ch.r, ch.eta, wo)) {
            continue;
        }
        if (std::abs(dot(wi, ch.r)) < 0.1 || std::abs(dot(wo, ch.r)) < 0.1) continue;
        // Off the manifold by up to ~0.2 rad in a third of the cases.
        if (chains.size() % 3 == 2) wo = normalize(wo + 0.2 * randomDir(rng));
        ch.prev = x + 1.3 * wi;
        ch.next = x + 0.9 * wo;
        ch.dprev = randomDir(rng);
        ch.dnext = randomDir(rng);
        ch.frameDir = wo;
        int mode = int(chains.size() / 2) % 3;  // vertex only, neighbours only, all
        ch.wx = mode == 1 ? 0 : 1;
        ch.wn = mode == 0 ? 0 : 1;
        chains.push_back(ch);
    }
    const double h = 1.6e-2;
    uint32_t n = uint32_t(chains.size());
    ImageData in = ImageData::make(5 * n, 9, 4);
    for (uint32_t i = 0; i < n; ++i) {
        fill(in, 5 * i, chains[i], -h, 1.0);
        fill(in, 5 * i + 1, chains[i], +h, 1.0);
        fill(in, 5 * i + 2, chains[i], -h / 2, 1.0);
        fill(in, 5 * i + 3, chains[i], +h / 2, 1.0);
        fill(in, 5 * i + 4, chains[i], 0.0, 1.0);
    }
    expectDerivativesMatch(runKernel("manifold_derivatives.comp", in), n, h,
                           "angle-difference derivative");
}

V rotate(V v, V k, double a) {  // Rodrigues, unit axis k
    return std::cos(a) * v + std::sin(a) * cross(k, v) + ((1 - std::cos(a)) * dot(k, v)) * k;
}

TEST(ManifoldConstraints, HalfVectorDerivativeMatchesFiniteDifferences) {
    // w_i and w_o turned towards random vectors, the tangent frame (s, t, n) rotated about a
    // random axis: w(e) = normalize(w + e a), frame(e) = R_k(e) frame.
    std::mt19937 rng(9);
    struct Hv {
        V wi, wo, n, s, t, a, b, k;
        bool reflection;
    };
    std::vector<Hv> cs;
    while (cs.size() < 192) {
        Hv c;
        c.n = randomDir(rng);
        c.s = normalize(cross(c.n, randomDir(rng)));
        c.t = cross(c.n, c.s);
        c.wi = randomDir(rng);
        c.reflection = cs.size() % 2 == 0;
        if (c.reflection) {
            if (dot(c.wi, c.n) < 0.1) continue;
            c.wo = reflect(c.wi, c.n);
        } else if (!refract(c.wi, c.n, 1.5, c.wo)) {
            continue;
        }
        if (std::abs(dot(c.wi, c.n)) < 0.1 || std::abs(dot(c.wo, c.n)) < 0.1) continue;
        if (cs.size() % 3 == 2) c.wo = normalize(c.wo + 0.2 * randomDir(rng));
        c.a = randomDir(rng);
        c.b = randomDir(rng);
        c.k = randomDir(rng);
        cs.push_back(c);
    }
    const double h = 1.6e-2;
    uint32_t n = uint32_t(cs.size());
    ImageData in = ImageData::make(5 * n, 9, 4);
    double steps[5] = {-h, h, -h / 2, h / 2, 0};
    for (uint32_t i = 0; i < n; ++i)
        for (int j = 0; j < 5; ++j) {
            const Hv& c = cs[i];
            double e = steps[j];
            V wi = normalize(c.wi + e * c.a), wo = normalize(c.wo + e * c.b);
            V rows[9] = {wi,
                         wo,
                         rotate(c.n, c.k, e),
                         rotate(c.s, c.k, e),
                         rotate(c.t, c.k, e),
                         c.a + (-dot(c.a, c.wi)) * c.wi,
                         c.b + (-dot(c.b, c.wo)) * c.wo,
                         cross(c.k, c.s),
                         cross(c.k, c.t)};
            for (uint32_t y = 0; y < 9; ++y) {
                uint32_t x = 5 * i + j;
                in.at(x, y, 0) = float(rows[y].x);
                in.at(x, y, 1) = float(rows[y].y);
                in.at(x, y, 2) = float(rows[y].z);
                in.at(x, y, 3) = 0.0f;
            }
            in.at(5 * i + j, 2, 3) = 1.5f;
            in.at(5 * i + j, 3, 3) = c.reflection ? 1.0f : 0.0f;
        }
    expectDerivativesMatch(runKernel("manifold_half_vector.comp", in), n, h,
                           "half-vector derivative");
}

}  // namespace
}  // namespace loom
