// Specular manifold sampling (passes/sms, shaders/lib/manifold): the walk against closed-form
// solutions (mirror image source, Snell's law on a flat interface, a sphere's reflection), the
// generalized geometric term against finite differences of re-solved chains, the Bernoulli
// estimator's E[K] = 1/p, unbiasedness against the reference path tracer, double counting,
// and bad input. Tolerances come from measured standard errors or from float precision stated
// where used.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <glm/glm.hpp>
#include <random>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneLoader.h"
#include "tests/support/CausticScenes.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/KernelColumns.h"
#include "tests/support/RegionStats.h"
#include "tests/support/ReuseComparison.h"
#include "tests/support/RoughCasters.h"
#include "tests/support/TestSupport.h"

namespace loom {
namespace {

using test::runColumns;
using test::sceneFromJson;
using test::sourcePath;

using test::kMirrorScene;

struct WalkInput {
    glm::vec3 x0, ng0, y, ny, seed;
    bool straight = false;
    bool directional = false;  // y is the unit direction towards a directional light
    int constraint = 0;        // 0 angle difference, 1 half vector
    int maxIterations = 20;
    float threshold = 1e-5f;
    int maxChain = 2;
    glm::vec3 es{1, 0, 0}, et{0, 0, 1};
    int stepControl = 0;  // 0 reprojection, 1 descent (MANIFOLD_STEP_*)
};
struct WalkResult {
    int phase, iterations, k;
    float det, beta, error;
    glm::vec3 v[4];
    float prim[4];
    glm::vec3 ng1;
};
constexpr int kConverged = 3;

// Runs a test kernel over columns: column i reads rows in[i][0..], writes outRows rows.
std::vector<WalkResult> runWalks(const scene::Scene& scene, const std::vector<WalkInput>& in) {
    std::vector<std::vector<glm::vec4>> cols;
    for (const auto& w : in)
        cols.push_back({glm::vec4(w.x0, 0), glm::vec4(w.ng0, 0), glm::vec4(w.y, 0),
                        glm::vec4(w.ny, w.directional ? 1 : 0),
                        glm::vec4(w.seed, w.straight ? 1 : 0),
                        glm::vec4(w.constraint, w.maxIterations, w.threshold, w.maxChain),
                        glm::vec4(w.es, w.stepControl), glm::vec4(w.et, 0)});
    auto out = runColumns(scene, "passes/sms/tests/manifold_walk.comp", cols, 8);
    std::vector<WalkResult> res(in.size());
    for (size_t i = 0; i < in.size(); ++i) {
        glm::vec4 a = out[i][0], b = out[i][5];
        res[i] = {int(a.x), int(a.y), int(a.z), a.w, b.x, b.y, {}};
        for (int j = 0; j < 4; ++j) {
            res[i].v[j] = glm::vec3(out[i][1 + j]);
            res[i].prim[j] = out[i][1 + j].w;
        }
        res[i].ng1 = glm::vec3(out[i][6]);
    }
    return res;
}

TEST(SpecularManifoldWalk, FlatMirrorConvergesToTheImageSourcePoint) {
    test::TempDir dir("loom-sms");
    auto scene = sceneFromJson(kMirrorScene, dir);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<WalkInput> in;
    glm::vec3 light(0.3f, 1.0f, 0.0f);
    for (int i = 0; i < 64; ++i) {
        WalkInput w;
        w.x0 = glm::vec3(u(rng) * 0.8f, 0, u(rng) * 0.8f);
        w.ng0 = glm::vec3(0, 1, 0);
        w.y = light;
        w.ny = glm::vec3(0);
        w.seed = glm::vec3(u(rng) * 0.9f, 2, u(rng) * 0.9f);
        w.constraint = i % 2;
        in.push_back(w);
    }
    auto res = runWalks(scene, in);
    int converged = 0;
    for (size_t i = 0; i < in.size(); ++i) {
        // Image source y' = (0.3, 3, 0): the reflection point is where x0 -> y' crosses y = 2.
        glm::vec3 img(light.x, 3.0f, light.z);
        float t = (2.0f - in[i].x0.y) / (img.y - in[i].x0.y);
        glm::vec3 expect = in[i].x0 + t * (img - in[i].x0);
        if (std::abs(expect.x) > 1 || std::abs(expect.z) > 1) continue;
        EXPECT_EQ(res[i].phase, kConverged)
            << "walk " << i << " iterations " << res[i].iterations << " k " << res[i].k << " beta "
            << res[i].beta << " error " << res[i].error << " v0 " << res[i].v[0].x << ","
            << res[i].v[0].y << "," << res[i].v[0].z << " expected " << expect.x << "," << expect.z;
        if (res[i].phase != kConverged) continue;
        ++converged;
        EXPECT_EQ(res[i].k, 1);
        EXPECT_LT(glm::length(res[i].v[0] - expect), 1e-4f) << "walk " << i;
        EXPECT_LT(res[i].error, 1e-5f);
    }
    EXPECT_GT(converged, 40);
}

// A mirror sphere (radius 0.5 at (0, 1, 0)) over the floor, a point light beside it: the
// reflection point lies on the great circle through x0 and the light, where the normal bisects
// the directions to both (Alhazen's problem, solved here by bisection in double).
TEST(SpecularManifoldWalk, MirrorSphereConvergesToTheReflectionPoint) {
    test::TempDir dir("loom-sms");
    auto scene = sceneFromJson(R"({
      "loom_scene": 1,
      "camera": {"origin": [0, 1.5, 3], "target": [0, 0.5, 0], "up": [0, 1, 0], "fov": 40},
      "materials": {"mirror": {"type": "conductor", "metal": "none"},
                    "floor": {"type": "diffuse", "reflectance": 0.5}},
      "shapes": [
        {"name": "floor", "type": "rectangle", "material": "floor", "caustic_receiver": true,
         "transform": [{"scale": 4}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}]},
        {"name": "ball", "type": "sphere", "center": [0, 1, 0], "radius": 0.5, "rings": 128,
         "segments": 256, "material": "mirror", "caustic_caster": true}],
      "lights": [{"type": "point", "position": [1.2, 0.7, 0.3], "intensity": 1, "caustic_emitter": true}]
    })",
                               dir);
    const glm::dvec3 c(0, 1, 0), light(1.2, 0.7, 0.3);
    const double R = 0.5;
    auto reflectionPoint = [&](glm::dvec3 x0) {
        glm::dvec3 a = glm::normalize(x0 - c), b = light - c;
        glm::dvec3 v = glm::normalize(b - a * glm::dot(a, b));
        double phiL = std::atan2(glm::dot(b, v), glm::dot(b, a));
        auto at = [&](double phi) { return c + R * (std::cos(phi) * a + std::sin(phi) * v); };
        auto f = [&](double phi) {  // angle to x0 minus angle to the light, about the normal
            glm::dvec3 p = at(phi), n = (p - c) / R;
            return std::acos(glm::dot(n, glm::normalize(x0 - p))) -
                   std::acos(glm::dot(n, glm::normalize(light - p)));
        };
        double lo = 0, hi = phiL;  // f(lo) < 0 < f(hi)
        for (int i = 0; i < 100; ++i) {
            double mid = 0.5 * (lo + hi);
            (f(mid) < 0 ? lo : hi) = mid;
        }
        return at(0.5 * (lo + hi));
    };
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<WalkInput> in;
    std::vector<glm::dvec3> expect;
    for (int i = 0; i < 64; ++i) {
        WalkInput w;
        w.x0 = glm::vec3(-0.9f + 0.4f * u(rng), 0, 0.4f * u(rng));
        w.ng0 = glm::vec3(0, 1, 0);
        w.y = glm::vec3(light);
        w.ny = glm::vec3(0);
        glm::dvec3 p = reflectionPoint(glm::dvec3(w.x0));
        expect.push_back(p);
        // Seeds on the sphere within ~25 degrees of the solution.
        glm::vec3 d = glm::normalize(glm::vec3(p - c) + 0.2f * glm::vec3(u(rng), u(rng), u(rng)));
        w.seed = glm::vec3(c) + 0.5f * d;
        w.constraint = i % 2;
        w.maxChain = 1;
        in.push_back(w);
    }
    auto res = runWalks(scene, in);
    int converged = 0;
    double worst = 0;
    for (size_t i = 0; i < in.size(); ++i) {
        if (res[i].phase != kConverged) continue;
        ++converged;
        EXPECT_EQ(res[i].k, 1);
        double err = glm::length(glm::dvec3(res[i].v[0]) - expect[i]);
        worst = std::max(worst, err);
        // The mesh's interpolated normals are the sphere's to O(spacing^2 / R^2) (spacing
        // pi R / 128): the reflection point moves by about R times that, 1e-4.
        EXPECT_LT(err, 5e-4) << "walk " << i << " (constraint " << in[i].constraint << ")";
    }
    EXPECT_GT(converged, 48);  // measured 58
    std::printf("mirror sphere: %d / 64 converge, worst distance to the reflection point %.2e\n",
                converged, worst);
}

using test::poolScene;

// The flat pool (poolScene) with a point light above it: walks from the floor refract out of the
// water and converge to the refraction point of Snell's law, found here by bisection in the
// plane of incidence. The same 64 seeds walk with each constraint and step control. The
// half-vector constraint saturates (|C| -> 1) where the walk overshoots, so with the reference's
// step control (halve only when the re-trace leaves the surface) most of its walks diverge;
// descent (also halve when max |C_i| does not fall) must rescue them.
TEST(SpecularManifoldWalk, FlatInterfaceConvergesToTheSnellPoint) {
    test::TempDir dir("loom-sms");
    auto scene = sceneFromJson(
        poolScene(
            R"({"type": "point", "position": [0.4, 2, -0.2], "intensity": 1, "caustic_emitter": true})"),
        dir);
    const glm::dvec3 light(0.4, 2, -0.2);
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<WalkInput> seeds;
    for (int i = 0; i < 64; ++i) {
        WalkInput w;
        w.x0 = glm::vec3(1.5f * u(rng), 0, 1.5f * u(rng));
        w.ng0 = glm::vec3(0, 1, 0);
        w.y = glm::vec3(light);
        w.ny = glm::vec3(0);
        w.seed = glm::vec3(2.5f * u(rng), 1, 2.5f * u(rng));
        seeds.push_back(w);
    }
    struct Mode {
        const char* name;
        int constraint, stepControl;
    };
    const Mode modes[] = {{"angle difference, reprojection", 0, 0},
                          {"angle difference, descent", 0, 1},
                          {"half vector, reprojection", 1, 0},
                          {"half vector, descent", 1, 1}};
    std::vector<WalkInput> in;
    for (const Mode& m : modes)
        for (WalkInput w : seeds) {
            w.constraint = m.constraint;
            w.stepControl = m.stepControl;
            in.push_back(w);
        }
    auto res = runWalks(scene, in);
    int converged[4] = {};
    for (size_t i = 0; i < in.size(); ++i) {
        glm::dvec3 x0(in[i].x0);
        glm::dvec3 flat = light - x0;
        flat.y = 0;
        double D = glm::length(flat), lo = 0, hi = D;
        for (int it = 0; it < 200; ++it) {  // 1.33 sin(theta_water) = sin(theta_air)
            double a = 0.5 * (lo + hi);
            double f = 1.33 * a / std::sqrt(a * a + 1) - (D - a) / std::sqrt((D - a) * (D - a) + 1);
            (f > 0 ? hi : lo) = a;
        }
        glm::dvec3 expect = x0 + glm::dvec3(0, 1, 0) + (D > 0 ? lo / D : 0.0) * flat;
        if (res[i].phase != kConverged) continue;
        ++converged[i / seeds.size()];
        EXPECT_EQ(res[i].k, 1);
        EXPECT_LT(glm::length(glm::dvec3(res[i].v[0]) - expect), 1e-4)
            << modes[i / seeds.size()].name << ", walk " << i % seeds.size();
    }
    for (int m = 0; m < 4; ++m)
        std::printf("flat interface, %s: %d of %zu walks converged\n", modes[m].name, converged[m],
                    seeds.size());
    // Seeds past the critical angle start from total internal reflection and some fail.
    EXPECT_GT(converged[0], 32);
    EXPECT_GT(converged[1], 32);
    EXPECT_GT(converged[3], 40);
    // Why descent exists: without it the half-vector walks mostly diverge.
    EXPECT_LT(converged[2], converged[3] - 16);
}

TEST(SpecularManifoldSampling, PoolUnderDirectionalLightMatchesClosedForm) {
    test::expectPoolDirectionalClosedForm(
        {{"name", "sms"}, {"type", "SpecularManifoldSampling"}, {"params", {{"maxChain", 1}}}}, 32,
        "sms");
}

TEST(SpecularManifoldSampling, PoolUnderPointLightMatchesClosedForm) {
    test::expectPoolPointClosedForm(
        {{"name", "sms"}, {"type", "SpecularManifoldSampling"}, {"params", {{"maxChain", 1}}}}, 16,
        "sms");
}

// An environment ends the chain at infinity in a sampled direction. Flat water under a constant
// sky of radiance 1: every direction of the sky crosses the surface with (1 - F), and the
// transmitted flux lands on the floor, E = 2 pi int_0^{pi/2} (1 - F(theta)) cos sin dtheta
// (the floor points the camera sees lie well inside the surface's extent).
TEST(SpecularManifoldSampling, PoolUnderConstantSkyMatchesClosedForm) {
    const int n = 20000;
    double E = 0;
    for (int i = 0; i < n; ++i) {
        double t = (i + 0.5) / n * M_PI / 2;
        E += (1 - test::fresnelDielectric(std::cos(t), 1.33)) * std::cos(t) * std::sin(t);
    }
    E *= 2 * M_PI * (M_PI / 2) / n;
    double expect = 0.5 / M_PI * E;
    auto [stats, analytic] = test::poolCaustic(
        {{"name", "sms"}, {"type", "SpecularManifoldSampling"}, {"params", {{"maxChain", 1}}}},
        R"({"type": "constant", "radiance": 1, "caustic_emitter": true})",
        [&](glm::dvec3) { return expect; }, 256);
    double se = std::sqrt(stats.stderr2(0));
    EXPECT_LT(std::abs(stats.mean(0) - analytic), 3 * se + 1e-3 * analytic)
        << "sms " << stats.mean(0) << " +- " << se << " closed form " << analytic;
    std::printf("pool, constant sky: %.6f +- %.6f vs %.6f\n", stats.mean(0), se, analytic);
}

// The generalized geometric term's end-point Jacobian |det(dx1/dy)| of two-refraction chains
// through the glass sphere against central differences: move the light point along its plane,
// re-solve from the old solution, measure x1's motion in its tangent plane.
TEST(SpecularManifoldWalk, EndpointJacobianMatchesFiniteDifferencesThroughTheSphere) {
    auto scene = scene::loadScene(sourcePath("scenes/glass_sphere.json"));
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    const glm::vec3 lightCentre(0.6f, 3.0f, -0.3f), es(1, 0, 0), et(0, 0, 1);
    const float h = 4e-3f;
    auto base = [&](glm::vec3 x0, glm::vec3 y, glm::vec3 seed, int constraint) {
        WalkInput w;
        w.x0 = x0;
        w.ng0 = glm::vec3(0, 1, 0);
        w.y = y;
        w.ny = glm::vec3(0, -1, 0);
        w.seed = seed;
        w.constraint = constraint;
        w.threshold = 2e-7f;  // near float precision, so that solutions move by h J, not noise
        w.maxIterations = 40;
        w.es = es;
        w.et = et;
        return w;
    };
    // Base solves from random seeds on the sphere's upper half, towards the light.
    std::vector<WalkInput> in;
    for (int i = 0; i < 256; ++i) {
        glm::vec3 x0(-0.6f + 0.35f * u(rng), 0.0f, 0.3f + 0.35f * u(rng));
        glm::vec3 y = lightCentre + 0.1f * u(rng) * es + 0.1f * u(rng) * et;
        glm::vec3 d = glm::normalize(glm::vec3(u(rng), 1.0f + u(rng), u(rng)));
        in.push_back(base(x0, y, glm::vec3(0, 0.6f, 0) + 0.5f * d, i % 2));
    }
    auto first = runWalks(scene, in);
    std::vector<WalkInput> fd;
    std::vector<size_t> which;
    for (size_t i = 0; i < in.size() && which.size() < 48; ++i) {
        if (first[i].phase != kConverged || first[i].k != 2) continue;
        which.push_back(i);
        for (glm::vec3 dy : {h * es, -h * es, h * et, -h * et})
            fd.push_back(base(in[i].x0, in[i].y + dy, first[i].v[0], in[i].constraint));
    }
    ASSERT_GE(which.size(), 12u) << "too few two-refraction solutions to check";
    auto moved = runWalks(scene, fd);
    int checked = 0;
    double worst = 0;
    for (size_t j = 0; j < which.size(); ++j) {
        const auto* m = &moved[j * 4];
        if (m[0].phase != kConverged || m[1].phase != kConverged || m[2].phase != kConverged ||
            m[3].phase != kConverged)
            continue;
        const WalkResult& b = first[which[j]];
        // Interpolated normals are smooth within a triangle only: differences across an edge
        // measure the mesh's kinks, not the derivative.
        bool sameTriangles = true;
        for (int q = 0; q < 4; ++q)
            sameTriangles = sameTriangles && m[q].prim[0] == b.prim[0] && m[q].prim[1] == b.prim[1];
        if (!sameTriangles) continue;
        glm::vec3 n = glm::normalize(b.ng1);
        glm::vec3 s = glm::normalize(glm::cross(n, glm::vec3(0.3f, 0.5f, 0.7f))),
                  t = glm::cross(n, s);
        auto st = [&](glm::vec3 p) { return glm::vec2(glm::dot(p, s), glm::dot(p, t)); };
        glm::vec2 c0 = (st(m[0].v[0]) - st(m[1].v[0])) / (2 * h);
        glm::vec2 c1 = (st(m[2].v[0]) - st(m[3].v[0])) / (2 * h);
        double detFd = std::abs(double(c0.x) * c1.y - double(c0.y) * c1.x);
        double rel = std::abs(b.det - detFd) / detFd;
        worst = std::max(worst, rel);
        ++checked;
        EXPECT_LT(rel, 0.005) << "chain " << j << ": det " << b.det << " finite differences "
                              << detFd;
    }
    EXPECT_GE(checked, 10);
    std::printf("end-point Jacobian vs finite differences: %d chains, worst relative error %.4f\n",
                checked, worst);
}

// The Jacobian blocks of the constraints (dC_i/d(s,t) of the previous vertex or x0, of the
// vertex itself with its interpolated normal's change, of the next vertex or y) against central
// differences: reflection off the curved mirror, two refractions through the glass sphere (one
// from inside), refraction at the wavy water under a directional light (w_o fixed), both
// constraint kinds, end-point columns for area and point lights. Chains are walk solutions
// moved off the manifold inside their triangles, so that C != 0 too.
TEST(SpecularManifoldWalk, ConstraintDerivativesMatchFiniteDifferences) {
    struct Case {
        const char* scene;
        int k;
        bool directional;
        glm::vec3 x0lo, x0hi, y, seedCentre;
        float seedSpread;
        float lightNormalY;  // the area light faces up (1) or down (-1)
        // > 0: the casters turn rough (Beckmann alpha) for the differences, and their
        // vertices scatter about sampled offset normals (MANIFOLD_ROUGH_CASTERS).
        float roughAlpha = 0.0f;
    };
    std::vector<Case> cases = {{"scenes/curved_mirror.json",
                                1,
                                false,
                                {-0.5f, 0, -0.5f},
                                {0.5f, 0, 0.5f},
                                {0.4f, 0.6f, -0.2f},
                                {0, 1.8f, 0},
                                0.6f,
                                1.0f},
                               {"scenes/glass_sphere.json",
                                2,
                                false,
                                {-0.95f, 0, -0.05f},
                                {-0.25f, 0, 0.65f},
                                {0.6f, 3.0f, -0.3f},
                                {0, 0.9f, 0},
                                0.3f,
                                -1.0f},
                               {"scenes/water_pool.json",
                                1,
                                true,
                                {-1.2f, 0, -0.8f},
                                {1.2f, 0, 0.8f},
                                glm::normalize(glm::vec3(0.3f, 1, 0.4f)),
                                {0, 0.8f, 0},
                                1.0f,
                                0.0f},
                               // A tangent-space normal map on a flat interface: the map's bilinear
                               // texels, the interpolated normal and the tangent frame all move n.
                               {"scenes/normal_mapped_water.json",
                                1,
                                false,
                                {-0.8f, 0, -0.8f},
                                {0.8f, 0, 0.8f},
                                {0.3f, 3.0f, -0.2f},
                                {0, 1.0f, 0},
                                0.8f,
                                -1.0f}};
    // Rough casters: the mirror and the sphere again, their vertices scattering about offset
    // normals that turn with the vertex's frame.
    for (auto [base, alpha] : {std::pair{0, 0.3f}, std::pair{1, 0.1f}}) {
        Case rough = cases[size_t(base)];
        rough.roughAlpha = alpha;
        cases.push_back(rough);
    }
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0, 1);
    const float h = std::getenv("LOOM_FD_H") ? float(std::atof(std::getenv("LOOM_FD_H"))) : 1e-3f;
    double worst = 0;
    int checked = 0;
    for (const Case& cs : cases) {
        auto scene = scene::loadScene(sourcePath(cs.scene));
        // Offset normals tilt some chains towards their angle frame's pole, where phi rounds
        // coarsely in float: there the differences' error goes as 1 / h (worst 5.5e-3, 2.5e-3,
        // 1.1e-3 at h = 5e-4, 1e-3, 2e-3; the half-vector rows of the same chains 1e-4).
        const float hc = cs.roughAlpha > 0 ? 2 * h : h;
        std::vector<WalkInput> walks;
        for (int i = 0; i < 96; ++i) {
            WalkInput w;
            w.x0 = cs.x0lo + (cs.x0hi - cs.x0lo) * glm::vec3(u(rng), u(rng), u(rng));
            w.ng0 = glm::vec3(0, 1, 0);
            w.y = cs.y + (cs.directional ? glm::vec3(0) : 0.05f * glm::vec3(u(rng), 0, u(rng)));
            w.ny = glm::vec3(0, cs.lightNormalY, 0);
            w.directional = cs.directional;
            w.seed = cs.seedCentre + cs.seedSpread * glm::vec3(2 * u(rng) - 1, 0, 2 * u(rng) - 1);
            w.constraint = i % 2;
            w.maxChain = cs.k;
            walks.push_back(w);
        }
        auto sol = runWalks(scene, walks);
        std::vector<std::vector<glm::vec4>> cols;
        std::vector<int> constraintOf;
        for (size_t i = 0; i < walks.size() && cols.size() < 24; ++i) {
            if (sol[i].phase != kConverged || sol[i].k != cs.k) continue;
            const WalkInput& w = walks[i];
            bool fromLight = !cs.directional && (cols.size() % 2 == 0);
            std::vector<glm::vec4> c = {glm::vec4(w.x0, w.constraint),
                                        glm::vec4(w.y, cs.directional),
                                        glm::vec4(0),
                                        glm::vec4(0),
                                        glm::vec4(1, 0, 0, cs.k),
                                        glm::vec4(0, 0, 1, fromLight),
                                        glm::vec4(hc, u(rng), u(rng), 0)};
            // Off the manifold, inside the triangle's plane (a move along ng's complement).
            for (int j = 0; j < cs.k; ++j) {
                glm::vec3 n = j == 0 ? glm::normalize(sol[i].ng1) : glm::vec3(0, 1, 0);
                glm::vec3 d(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f);
                d -= n * glm::dot(n, d);
                c[2 + j] = glm::vec4(sol[i].v[j] + (j == 0 ? 0.01f : 0.0f) * d, sol[i].prim[j]);
            }
            cols.push_back(c);
            constraintOf.push_back(w.constraint);
        }
        ASSERT_GE(cols.size(), 8u) << cs.scene << ": too few solutions to check";
        if (cs.roughAlpha > 0) {
            for (auto& m : scene.materials) {
                if (m.type == scene::BsdfType::Conductor) m.type = scene::BsdfType::RoughConductor;
                if (m.type == scene::BsdfType::Dielectric)
                    m.type = scene::BsdfType::RoughDielectric;
                m.alpha = cs.roughAlpha;
                m.distribution = scene::Microfacet::Beckmann;
            }
            ::setenv("LOOM_SHADER_DEFINES", "MANIFOLD_ROUGH_CASTERS=1", 1);
        }
        auto out = runColumns(scene, "passes/sms/tests/manifold_jacobian.comp", cols, 12);
        ::unsetenv("LOOM_SHADER_DEFINES");
        double caseWorst[2] = {0, 0};
        int caseChecked = 0, caseSkipped = 0;
        // Differences that leave a normal map's bilinear texel cell read -1e30 (skipped).
        auto skipped = [](glm::vec4 r) { return r.x < -1e29f; };
        for (size_t c = 0; c < cols.size(); ++c)
            for (int i = 0; i < cs.k; ++i) {
                // Scale: the largest column of the row (derivatives are per unit length).
                double scale = 0;
                for (int j = 0; j < 6; ++j)
                    if (!skipped(out[c][6 * i + j]))
                        scale = std::max(scale, double(glm::length(glm::vec2(out[c][6 * i + j]))));
                for (int j = 0; j < 6; ++j) {
                    glm::vec4 r = out[c][6 * i + j];
                    ASSERT_LT(r.x, 1e29f) << cs.scene << " chain " << c << ": constraint undefined";
                    if (skipped(r)) {
                        ++caseSkipped;
                        continue;
                    }
                    ++caseChecked;
                    double err = glm::length(glm::vec2(r.x - r.z, r.y - r.w)) / scale;
                    worst = std::max(worst, err);
                    caseWorst[constraintOf[c]] = std::max(caseWorst[constraintOf[c]], err);
                    ++checked;
                    // Extrapolated differences at h = 1e-3 in float: rounding ~ 1e-7 / h relative
                    // (measured worst 3.6e-4; 7e-4 at h = 5e-4, as rounding predicts). Leaving
                    // out the normal's change fails it at 0.63.
                    EXPECT_LT(err, 2e-3)
                        << cs.scene << " chain " << c << " row " << i << " column " << j << " ("
                        << (constraintOf[c] ? "half vector" : "angle difference") << "): analytic ("
                        << r.x << ", " << r.y << ") differences (" << r.z << ", " << r.w << ")";
                }
            }
        EXPECT_GE(caseChecked, 4 * caseSkipped) << cs.scene << ": most columns skipped";
        std::printf(
            "%s%s: %d columns, worst relative error %.2e (angle difference), %.2e (half "
            "vector); %d skipped (texel cell left)\n",
            cs.scene, cs.roughAlpha > 0 ? " (rough, offset normals)" : "", caseChecked,
            caseWorst[0], caseWorst[1], caseSkipped);
    }
    std::printf(
        "constraint derivatives vs finite differences: %d columns, worst relative error %.2e\n",
        checked, worst);
}

// Two flat mirrors facing down at y = 2 over a diffuse floor (albedo 0.5), a point light of
// intensity 1 at (0, 1, 0): mirror A (area 1) above the origin holds every reflection point the
// camera's floor region has; mirror B (area 3) far to the side holds none, so a seed converges
// with probability p = 1/4 exactly (seeds are uniform by area; a walk never leaves its shape).
const char* kTwoMirrorScene = R"({
  "loom_scene": 1,
  "camera": {"origin": [0, 1.5, 2.5], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 30},
  "materials": {"mirror": {"type": "conductor", "metal": "none"},
                "floor": {"type": "diffuse", "reflectance": 0.5}},
  "shapes": [
    {"name": "floor", "type": "rectangle", "material": "floor", "caustic_receiver": true,
     "transform": [{"scale": 6}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}]},
    {"name": "mirrorA", "type": "rectangle", "material": "mirror", "caustic_caster": true,
     "transform": [{"scale": 0.5}, {"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 2, 0]}]},
    {"name": "mirrorB", "type": "rectangle", "material": "mirror", "caustic_caster": true,
     "transform": [{"scale": [0.5, 1.5, 1]}, {"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [3.5, 2, 0]}]}],
  "lights": [{"type": "point", "position": [0, 1, 0], "intensity": 1, "caustic_emitter": true}]
})";

// The mirror caustic in closed form at floor point x: the image source y' = (0, 3, 0) seen
// through mirror A, L = rho / pi * I cos / d^2.
double twoMirrorCaustic(glm::dvec3 x) {
    glm::dvec3 img(0, 3, 0);
    glm::dvec3 r = x + (2.0 / 3.0) * (img - x);  // reflection point on y = 2
    if (std::abs(r.x) > 0.5 || std::abs(r.z) > 0.5) return 0.0;
    glm::dvec3 d = img - x;
    double d2 = glm::dot(d, d);
    return 0.5 / M_PI * (d.y / std::sqrt(d2)) / d2;
}

struct CausticRun {
    test::RegionStats caustic{1};
    double analytic = 0;        // the closed form over the same pixels
    double meanK = 0, seK = 0;  // Bernoulli trials of the estimates that found the solution
    int solved = 0;
};

// SMS on the two-mirror scene, pixel centres (GBuffer positions give the closed form there).
CausticRun runTwoMirror(const json& smsParams, int frames) {
    test::TempDir dir("loom-sms");
    auto scene = sceneFromJson(kTwoMirrorScene, dir);
    json g = {{"passes",
               {{{"name", "sms"}, {"type", "SpecularManifoldSampling"}, {"params", smsParams}},
                {{"name", "gbuf"}, {"type", "GBuffer"}, {"params", {{"jitter", false}}}}}},
              {"edges", json::array()},
              {"outputs", {"sms.caustic", "sms.stats", "gbuf.position"}}};
    constexpr uint32_t kSize = 16;
    Renderer r(test::gpuContext(), RenderGraph::parse(g.dump(), "<test>"), kSize, kSize, 1);
    r.setScene(scene);
    CausticRun run;
    double sumK = 0, sumK2 = 0;
    for (int f = 0; f < frames; ++f) {
        r.frame();
        ImageData c = r.readOutput("sms.caustic"), st = r.readOutput("sms.stats");
        if (f == 0) {
            ImageData pos = r.readOutput("gbuf.position");
            for (uint32_t y = 0; y < kSize; ++y)
                for (uint32_t x = 0; x < kSize; ++x)
                    run.analytic += twoMirrorCaustic(glm::dvec3(pos.at(x, y, 0), pos.at(x, y, 1),
                                                                pos.at(x, y, 2))) /
                                    double(kSize * kSize);
        }
        run.caustic.add(c);
        for (uint32_t y = 0; y < kSize; ++y)
            for (uint32_t x = 0; x < kSize; ++x)
                if (st.at(x, y, 1) > 0.5f) {  // solution found: walks = 1 + K
                    double K = st.at(x, y, 2) - 1.0;
                    sumK += K;
                    sumK2 += K * K;
                    ++run.solved;
                }
    }
    run.meanK = sumK / run.solved;
    run.seK = std::sqrt(std::max(sumK2 / run.solved - run.meanK * run.meanK, 0.0) / run.solved);
    return run;
}

TEST(SpecularManifoldSampling, BernoulliTrialsAverageOneOverTheConvergenceProbability) {
    auto run = runTwoMirror({{"estimator", "unbiased"}}, 32);
    ASSERT_GT(run.solved, 1000);
    // E[K] = 1 / p = 4, K geometric: SE from the measured spread.
    EXPECT_LT(std::abs(run.meanK - 4.0), 3.0 * run.seK)
        << "mean K " << run.meanK << " +- " << run.seK << " over " << run.solved;
    // The estimate f K against the closed form (pixels with no solution read 0 in both).
    double se = std::sqrt(run.caustic.stderr2(0));
    EXPECT_LT(std::abs(run.caustic.mean(0) - run.analytic), 3.0 * se + 2e-3 * run.analytic)
        << "sms " << run.caustic.mean(0) << " +- " << se << " closed form " << run.analytic;
    std::printf("two mirrors: E[K] = %.4f +- %.4f (1/p = 4), caustic %.6f +- %.6f vs %.6f\n",
                run.meanK, run.seK, run.caustic.mean(0), se, run.analytic);
}

// The trial cap's two behaviours, in closed form at p = 1/4 and maxTrials = 2. An estimate
// exists when the sample's own walk converges (probability p) and is f K, E = f. Drop keeps it
// only when the first Bernoulli trial succeeds: E = p * p f = f / 16. Keep uses min(K, 2):
// E = p f (p + 2 (1 - p)) = 0.4375 f.
TEST(SpecularManifoldSampling, TrialCapDropsOrKeepsAsDeclared) {
    auto drop =
        runTwoMirror({{"estimator", "unbiased"}, {"maxTrials", 2}, {"trialCap", "drop"}}, 8);
    auto keep =
        runTwoMirror({{"estimator", "unbiased"}, {"maxTrials", 2}, {"trialCap", "keep"}}, 8);
    double seDrop = std::sqrt(drop.caustic.stderr2(0)), seKeep = std::sqrt(keep.caustic.stderr2(0));
    EXPECT_LT(std::abs(drop.caustic.mean(0) - drop.analytic / 16.0),
              3.0 * seDrop + 2e-3 * drop.analytic)
        << "drop: " << drop.caustic.mean(0) << " +- " << seDrop << ", expected "
        << drop.analytic / 16.0;
    EXPECT_LT(std::abs(keep.caustic.mean(0) - 0.4375 * keep.analytic),
              3.0 * seKeep + 2e-3 * keep.analytic)
        << "keep: " << keep.caustic.mean(0) << " +- " << seKeep << ", expected "
        << 0.4375 * keep.analytic;
}

struct UnbiasedCheck {
    double z;        // worst |z| over the regions
    double sms, pt;  // the means there
};

// SMS (full image: the path part without covered paths + the caustic) against the reference
// path tracer, luminance over regions x regions blocks.
UnbiasedCheck compareWithPathTracer(const scene::Scene& scene, const json& overrides, int smsFrames,
                                    int ptFrames, int ptSpp, int regions) {
    constexpr uint32_t kSize = 32;
    auto sms = test::frameStats(test::loadGraph("sms.json", overrides), scene, {"sms.color"},
                                smsFrames, regions, kSize, 11)[0];
    auto pt = test::frameStats(test::ptGraph(ptSpp, 9), scene, {"pt.color"}, ptFrames, regions,
                               kSize, 23)[0];
    UnbiasedCheck c;
    c.z = test::maxZ(sms, pt, &c.sms, &c.pt);
    for (int i = 0; i < regions * regions; ++i)
        std::printf("region %d: sms %.5f +- %.5f  pt %.5f +- %.5f\n", i, sms.mean(i * 3),
                    std::sqrt(sms.stderr2(i * 3)), pt.mean(i * 3), std::sqrt(pt.stderr2(i * 3)));
    return c;
}

// SMS against the path tracer (default settings, 64 reference frames of 32 spp, 2 x 2 regions):
// |z| < 3 everywhere.
void expectUnbiased(const scene::Scene& scene, int smsFrames, int ptFrames = 64) {
    auto c = compareWithPathTracer(scene, {}, smsFrames, ptFrames, 32, 2);
    EXPECT_LT(c.z, 3.0) << "sms " << c.sms << " pt " << c.pt;
}

// The same comparison with an ablation compiled in (LOOM_SHADER_DEFINES): it must fail, |z| > 6.
void expectAblationDetected(const scene::Scene& scene, const char* define, int smsFrames) {
    ::setenv("LOOM_SHADER_DEFINES", define, 1);
    auto c = compareWithPathTracer(scene, {}, smsFrames, 64, 32, 2);
    ::unsetenv("LOOM_SHADER_DEFINES");
    EXPECT_GT(c.z, 6.0) << define << " went unseen: sms " << c.sms << " pt " << c.pt;
    std::printf("%s: worst |z| %.1f (sms %.5f, pt %.5f)\n", define, c.z, c.sms, c.pt);
}

TEST(SpecularManifoldSampling, UnbiasedOnTheGlassSphereAgainstThePathTracer) {
    expectUnbiased(scene::loadScene(sourcePath("scenes/glass_sphere.json")), 256);
}

TEST(SpecularManifoldSampling, UnbiasedOnTheCurvedMirrorAgainstThePathTracer) {
    expectUnbiased(scene::loadScene(sourcePath("scenes/curved_mirror.json")), 128);
}

// Two refractions with normal variation at both vertices (the wavy slab's faces differ).
TEST(SpecularManifoldSampling, UnbiasedThroughTheWavySlabAgainstThePathTracer) {
    int scale = std::getenv("LOOM_SLAB_SCALE") ? std::atoi(std::getenv("LOOM_SLAB_SCALE")) : 1;
    expectUnbiased(scene::loadScene(sourcePath("scenes/wavy_slab.json")), 128 * scale, 64 * scale);
}

// A normal-mapped caster (the shared SMS scenes' kind): the walk scatters about the mapped
// normal, as the path tracer does, and differentiates it, texels included.
TEST(SpecularManifoldSampling, UnbiasedThroughANormalMappedSurfaceAgainstThePathTracer) {
    expectUnbiased(scene::loadScene(sourcePath("scenes/normal_mapped_water.json")), 128);
}

// The same comparison must see a walk that leaves the texels' change out of the normal's
// derivative: it still converges to the same chains (Newton with a wrong Jacobian), but the
// generalized geometric term, which solves with that Jacobian, is wrong.
TEST(SpecularManifoldSampling, NormalMapDerivativeLeftOutIsDetected) {
    expectAblationDetected(scene::loadScene(sourcePath("scenes/normal_mapped_water.json")),
                           "LOOM_TEST_NORMAL_MAP_CONSTANT_TEXELS=1", 128);
}

// Receivers behind the camera path's specular prefix (receiverDepth): flat water (the
// normal-mapped scene without its map: one solution with a wide basin per floor point, so the
// estimate is nearly noiseless and the test's power is the path tracer's) seen from above, its
// floor through the surface. The estimate must carry the prefix's throughput: without it
// (LOOM_TEST_SMS_PREFIX_UNWEIGHTED) the floor under water brightens by 1 / beta.
TEST(SpecularManifoldSampling, UnbiasedAtReceiversSeenThroughWaterAgainstThePathTracer) {
    auto scene = scene::loadScene(sourcePath("scenes/normal_mapped_water.json"));
    for (auto& m : scene.materials) m.normalMap = -1;
    scene.camera.path.clear();
    scene.camera.toWorld = scene::lookAtMatrix({0, 2.2f, 1.6f}, {0, 0, -0.1f}, {0, 1, 0});
    expectUnbiased(scene, 128);
    expectAblationDetected(scene, "LOOM_TEST_SMS_PREFIX_UNWEIGHTED=1", 128);
}

// The same pool, full image against the path tracer (which finds the sky easily): the path part
// must leave out exactly the chains that end in the sky; kept
// (LOOM_TEST_KEEP_ENVIRONMENT_PATHS), they count twice.
TEST(SpecularManifoldSampling, UnbiasedUnderAnEnvironmentAgainstThePathTracer) {
    test::TempDir dir("loom-sms-sky");
    auto scene = test::sceneFromJson(
        test::poolScene(R"({"type": "constant", "radiance": 1, "caustic_emitter": true})"), dir);
    expectUnbiased(scene, 64, 32);
    expectAblationDetected(scene, "LOOM_TEST_KEEP_ENVIRONMENT_PATHS=1", 64);
}

// The bias class the exclusion prevents: with the covered paths left in the path part, the
// image brightens by the caustic, and the same comparison must see it.
TEST(SpecularManifoldSampling, DoubleCountingIsDetected) {
    auto scene = scene::loadScene(sourcePath("scenes/curved_mirror.json"));
    auto c = compareWithPathTracer(scene, {{"sms.excludeCovered", false}}, 128, 64, 32, 2);
    EXPECT_GT(c.z, 6.0) << "double counting went unseen: sms " << c.sms << " pt " << c.pt;
    EXPECT_GT(c.sms, c.pt);
    std::printf("double counting: worst |z| %.1f (sms %.5f, pt %.5f)\n", c.z, c.sms, c.pt);
}

// Receivers behind a diffuse bounce (maxReceivers): scenes/curved_mirror_wall.json, whose floor
// is lit only through the mirror, with a wall behind; the camera sees mostly the wall (top
// regions). The floor's caustic lights the wall through one diffuse bounce: SMS at the floor
// (the path's second receiver) estimates it, where the path tracer finds it only by chance.
// Without the estimates at later receivers (LOOM_TEST_LATER_RECEIVERS_LOST) those paths are
// lost: the path part still leaves them out.
TEST(SpecularManifoldSampling, UnbiasedAtReceiversBehindADiffuseBounceAgainstThePathTracer) {
    auto scene = scene::loadScene(sourcePath("scenes/curved_mirror_wall.json"));
    const json twoReceivers = {{"sms.maxReceivers", 2}};
    auto pt = test::frameStats(test::ptGraph(32, 9), scene, {"pt.color"}, 64, 2, 32, 23)[0];
    double z[2];
    for (int lost = 0; lost < 2; ++lost) {
        if (lost) ::setenv("LOOM_SHADER_DEFINES", "LOOM_TEST_LATER_RECEIVERS_LOST=1", 1);
        auto sms = test::frameStats(test::loadGraph("sms.json", twoReceivers), scene, {"sms.color"},
                                    192, 2, 32, 11)[0];
        ::unsetenv("LOOM_SHADER_DEFINES");
        double a, b;
        z[lost] = test::maxZ(sms, pt, &a, &b);
        for (int i = 0; i < 4; ++i)
            std::printf("%s region %d: sms %.5f +- %.5f  pt %.5f +- %.5f\n",
                        lost ? "later receivers lost," : "two receivers,", i, sms.mean(i * 3),
                        std::sqrt(sms.stderr2(i * 3)), pt.mean(i * 3),
                        std::sqrt(pt.stderr2(i * 3)));
    }
    EXPECT_LT(z[0], 3.0);
    EXPECT_GT(z[1], 6.0);
    std::printf("two receivers: worst |z| %.2f; later receivers lost: %.1f\n", z[0], z[1]);
}

// Rough casters (Zeltner et al. 2020 Sec. 5.3): the project scene with its casters' materials
// made rough (distribution d, roughness alpha).
scene::Scene roughScene(const char* path, float alpha, scene::Microfacet d) {
    auto scene = scene::loadScene(sourcePath(path));
    test::makeCastersRough(scene, alpha, d);
    return scene;
}

// A rough flat mirror (Beckmann roughness alpha, F = 1) facing down at y = 2 over the floor, a
// point light of intensity 1 below it: SMS's caustic (64 x frames) and the same by quadrature
// over the mirror, with the microfacet terms written here in double, apart from microfacet.glsl
// (Walter et al. 2007 Eq. 25 for D, Smith's Lambda with std::erfc, Heitz 2014's
// height-correlated G2): E(x0) = int_mirror D(h) G2(c, l) I |c.n_floor| / (4 r_c^2 r_l^2) dA,
// c and l towards x0 and the light, since f_r |c.n| |l.n| = D G2 / 4.
struct RoughMirrorCheck {
    double sms, se, quadrature;
};
RoughMirrorCheck roughMirrorUnderPointLight(double alpha, int frames) {
    const glm::dvec3 light(0.3, 1, 0), n(0, -1, 0);
    std::string text = kMirrorScene;
    const std::string from = R"("mirror": {"type": "conductor", "metal": "none"})";
    text.replace(text.find(from), from.size(),
                 R"("mirror": {"type": "roughconductor", "metal": "none", "alpha": )" +
                     std::to_string(alpha) + R"(, "distribution": "beckmann"})");
    auto lambda = [&](glm::dvec3 w) {
        double c = glm::dot(w, n), t = std::sqrt(std::max(0.0, 1 - c * c)) / c;
        if (t <= 0) return 0.0;
        double a = 1 / (alpha * t);
        return 0.5 * (std::exp(-a * a) / (a * std::sqrt(M_PI)) - std::erfc(a));
    };
    auto caustic = [&](glm::dvec3 x0) {
        const int N = 240;  // midpoint rule; 600 changes the image mean by < 1e-5
        const double dA = (2.0 / N) * (2.0 / N);
        double E = 0;
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) {
                glm::dvec3 x1(-1 + (i + 0.5) * 2.0 / N, 2, -1 + (j + 0.5) * 2.0 / N);
                glm::dvec3 c = x0 - x1, l = light - x1;
                double rc2 = glm::dot(c, c), rl2 = glm::dot(l, l);
                c /= std::sqrt(rc2);
                l /= std::sqrt(rl2);
                glm::dvec3 h = glm::normalize(c + l);
                double cos_h = glm::dot(h, n), tan2 = (1 - cos_h * cos_h) / (cos_h * cos_h);
                double D = std::exp(-tan2 / (alpha * alpha)) /
                           (M_PI * alpha * alpha * cos_h * cos_h * cos_h * cos_h);
                double G2 = 1 / (1 + lambda(c) + lambda(l));
                E += D * G2 * std::abs(c.y) / (4 * rc2 * rl2) * dA;
            }
        return 0.5 / M_PI * E;
    };
    auto [stats, analytic] = test::floorCaustic(
        {{"name", "sms"}, {"type", "SpecularManifoldSampling"}, {"params", {{"maxChain", 1}}}},
        text, caustic, frames);
    RoughMirrorCheck r{stats.mean(0), std::sqrt(stats.stderr2(0)), analytic};
    std::printf("rough mirror (alpha %.2f), point light: %.6f +- %.6f vs quadrature %.6f\n", alpha,
                r.sms, r.se, r.quadrature);
    return r;
}

// The offset normal turns the flat mirror into a surface that reflects about m != n_g, which
// changes a beam's etendue: the point light's flux form must be turned into the radiance form
// the path tracer carries (manifold_chain_throughput's etendue_scale). Kept as flux
// (LOOM_TEST_FLUX_FORM_KEPT), alpha 0.4 reads 3 % dark (measured |z| 6.2 at 256 frames).
TEST(SpecularManifoldSampling, RoughMirrorUnderPointLightMatchesQuadrature) {
    auto r = roughMirrorUnderPointLight(0.2, 64);
    // Pixel-centre quadrature vs the jittered estimate: the rough caustic is smooth (at 48 x 48
    // pixels the same comparison reads the same).
    EXPECT_LT(std::abs(r.sms - r.quadrature), 3 * r.se + 5e-3 * r.quadrature);
    ::setenv("LOOM_SHADER_DEFINES", "LOOM_TEST_FLUX_FORM_KEPT=1", 1);
    auto flux = roughMirrorUnderPointLight(0.4, 256);
    ::unsetenv("LOOM_SHADER_DEFINES");
    EXPECT_GT(std::abs(flux.sms - flux.quadrature), 4 * flux.se + 5e-3 * flux.quadrature)
        << "the point light's flux form went unseen";
}

// Unbiased SMS with rough casters (offset normals, trials that keep them) against the path
// tracer: a GGX mirror and a Beckmann glass sphere (two rough refractions).
TEST(SpecularManifoldSampling, UnbiasedThroughRoughCastersAgainstThePathTracer) {
    expectUnbiased(roughScene("scenes/curved_mirror.json", 0.1f, scene::Microfacet::GGX), 128);
    expectUnbiased(roughScene("scenes/glass_sphere.json", 0.1f, scene::Microfacet::Beckmann), 128);
}

// At a rough caster vertex the path tracer's light sample reaches the emitter as its BSDF
// sample does: both must leave the covered paths out. Light samples kept
// (LOOM_TEST_ROUGH_LIGHT_SAMPLES_KEPT) count the caustic about twice. And the rough vertex's
// weight G2 |c.m| / (|c.n| |m.n|) beyond the density (left out:
// LOOM_TEST_ROUGH_WEIGHT_OMITTED) shows at alpha 0.4.
TEST(SpecularManifoldSampling, RoughCasterAblationsAreDetected) {
    expectAblationDetected(roughScene("scenes/curved_mirror.json", 0.1f, scene::Microfacet::GGX),
                           "LOOM_TEST_ROUGH_LIGHT_SAMPLES_KEPT=1", 128);
    expectAblationDetected(
        roughScene("scenes/curved_mirror.json", 0.4f, scene::Microfacet::Beckmann),
        "LOOM_TEST_ROUGH_WEIGHT_OMITTED=1", 512);
}

// MNEE's seed for a reflective caster is its bounding-box centre (the reference code's: the
// straight line to the light never reflects, and read 3% of the curved mirror's caustic). MNEE
// is biased (one solution per estimate): per region never above unbiased SMS, and on this
// mirror, with one reflection point per floor point, nearly all of it.
TEST(SpecularManifoldSampling, MneeSeedsReflectiveCastersAtTheirCentre) {
    auto scene = scene::loadScene(sourcePath("scenes/curved_mirror.json"));
    auto mnee =
        test::frameStats(test::loadGraph("mnee.json"), scene, {"sms.caustic"}, 32, 2, 32, 11)[0];
    auto sms =
        test::frameStats(test::loadGraph("sms.json"), scene, {"sms.caustic"}, 32, 2, 32, 29)[0];
    double a = 0, b = 0;
    for (int i = 0; i < 4; ++i) {
        double se = std::sqrt(mnee.stderr2(i * 3) + sms.stderr2(i * 3));
        EXPECT_LT(mnee.mean(i * 3), sms.mean(i * 3) + 3 * se) << "region " << i;
        a += mnee.mean(i * 3);
        b += sms.mean(i * 3);
        std::printf("region %d: mnee %.5f, sms %.5f +- %.5f\n", i, mnee.mean(i * 3),
                    sms.mean(i * 3), std::sqrt(sms.stderr2(i * 3)));
    }
    EXPECT_GT(a, 0.9 * b) << "MNEE found " << a / b << " of the mirror's caustic";
    std::printf("MNEE / unbiased SMS on the curved mirror: %.4f\n", a / b);
}

// Bad input: each mistake is one named error (no silent black caustic).
TEST(SpecularManifoldSampling, BadCausticTagsAreNamedErrors) {
    test::TempDir dir("loom-sms-bad");
    auto expectThrows = [&](const std::string& sceneText, const std::string& what, bool atLoad) {
        try {
            auto scene = sceneFromJson(sceneText, dir);
            ASSERT_FALSE(atLoad) << "loading should fail: " << what;
            Renderer r(test::gpuContext(), test::loadGraph("sms.json"), 8, 8, 1);
            r.setScene(scene);
            r.frame();
            FAIL() << "rendering should fail: " << what;
        } catch (const UserError& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    auto edit = [](std::string text, const std::string& from, const std::string& to) {
        text.replace(text.find(from), from.size(), to);
        return text;
    };
    expectThrows(edit(kMirrorScene, "\"caustic_receiver\": true,", ""),
                 "casters but no caustic receivers", false);
    expectThrows(edit(kMirrorScene, "\"material\": \"mirror\"", "\"material\": \"floor\""),
                 "caustic casters need a dielectric or conductor material", true);
    expectThrows(edit(kMirrorScene, "\"caustic_caster\"", "\"caustic_castr\""), "caustic_castr",
                 true);
    std::string noEmitter = edit(kMirrorScene, ", \"caustic_emitter\": true", "");
    expectThrows(noEmitter, "no caustic emitters", false);
}

}  // namespace
}  // namespace loom
