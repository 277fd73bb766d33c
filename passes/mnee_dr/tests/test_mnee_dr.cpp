// MNEE with dimension reduction (passes/mnee_dr, shaders/lib/manifold/coplanar_walk.glsl): the
// walk against Snell's law on a flat interface and the focusing factor against its closed
// form, D against finite differences of re-solved walks on a wavy surface (and a deliberately
// biased D that the test catches), agreement with the Newton MNEE of the SMS pass, mesh edge
// cases, the animated surface, and the image against unbiased SMS and the path tracer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
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
#include "tests/support/TestSupport.h"

namespace loom {
namespace {

using test::runColumns;
using test::sceneFromJson;

enum Status { kSolved, kNoStart, kBoundary, kCap, kTir, kDegenerate, kNoRoot };

// A caster shape (`caster`: a JSON shape object of material "water", a dielectric of IOR
// `ior`) over a diffuse floor receiver at y = -1, and `light`.
std::string casterScene(const std::string& caster, const std::string& light, double ior = 1.33) {
    return R"({
  "loom_scene": 1,
  "camera": {"origin": [0, 0.5, 3], "target": [0, -1, 0], "up": [0, 1, 0], "fov": 50},
  "materials": {"water": {"type": "dielectric", "ior": )" +
           std::to_string(ior) + R"(},
                "floor": {"type": "diffuse", "reflectance": 0.5}},
  "shapes": [
    {"name": "floor", "type": "rectangle", "material": "floor", "caustic_receiver": true,
     "transform": [{"scale": 3}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"translate": [0, -1, 0]}]},
    )" + caster +
           R"(],
  "lights": [)" +
           light + R"(]
})";
}

// A water surface: a heightfield over [-2, 2]^2 at y = 0, `height` in object units.
std::string waterScene(const std::string& height, int resolution, double ior,
                       const std::string& light, const std::string& extra = "") {
    return casterScene(
        R"({"name": "water", "type": "heightfield", "resolution": )" + std::to_string(resolution) +
            R"(, "material": "water", "caustic_caster": true, "height": ")" + height + R"(" )" +
            extra +
            R"(, "transform": [{"scale": 2}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}]})",
        light, ior);
}

const char* kPointLight =
    R"({"type": "point", "position": [0.3, 1.5, 0.2], "intensity": 1, "caustic_emitter": true})";

struct WalkOut {
    int status, triangles, bisections, prim;
    glm::vec3 M;
    float D, sine;
    int statusOther;  // how the other walk direction ended
    glm::vec2 bary;
};

struct Settings {
    int maxTriangles = 1000, maxBisections = 40;
    float tolerance = 1e-6f;
    bool both = true;
};

std::vector<WalkOut> runWalks(
    const scene::Scene& scene, const std::vector<glm::vec3>& P, const std::vector<glm::vec3>& L,
    bool directional = false, Settings s = {}, float time = 0.0f,
    const std::string& kernel = "passes/mnee_dr/tests/coplanar_walk.comp") {
    std::vector<std::vector<glm::vec4>> cols;
    for (size_t i = 0; i < P.size(); ++i)
        cols.push_back({glm::vec4(P[i], directional ? 1 : 0), glm::vec4(L[i], 0),
                        glm::vec4(s.maxTriangles, s.maxBisections, s.tolerance, s.both ? 1 : 0)});
    auto out = runColumns(scene, kernel, cols, 3, time);
    std::vector<WalkOut> res;
    for (auto& o : out)
        res.push_back({int(o[0].x), int(o[0].y), int(o[0].z), int(o[0].w), glm::vec3(o[1]), o[1].w,
                       o[2].z, int(o[2].w), glm::vec2(o[2])});
    return res;
}

// Flat interface y = 0, light at height hL above, P at depth hP, horizontal distance rho;
// eta = n_water / n_air. Snell's law in the plane of incidence by bisection (double), and the
// beam's cross-section per solid angle at P: D = rho (d rho / d theta1) cos theta2 / sin theta1.
struct FlatSolution {
    double x;  // horizontal distance from the light's foot to M
    double D;
};
FlatSolution flatSnell(double hL, double hP, double rho, double eta) {
    double lo = 0, hi = rho;
    auto g = [&](double x) {
        double s1 = x / std::hypot(x, hL), s2 = (rho - x) / std::hypot(rho - x, hP);
        return s1 - eta * s2;
    };
    for (int i = 0; i < 200; ++i) {
        double mid = 0.5 * (lo + hi);
        (g(mid) < 0 ? lo : hi) = mid;
    }
    double x = 0.5 * (lo + hi);
    double t1 = std::atan2(x, hL), t2 = std::asin(std::sin(t1) / eta);
    double drho = hL / (std::cos(t1) * std::cos(t1)) +
                  hP / (std::cos(t2) * std::cos(t2)) * std::cos(t1) / (eta * std::cos(t2));
    return {x, rho * drho * std::cos(t2) / std::sin(t1)};
}

void checkFlat(double ior) {
    test::TempDir dir("loom-mnee-dr");
    auto scene = sceneFromJson(waterScene("0", 16, ior, kPointLight), dir);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.6f, 1.6f);
    std::vector<glm::vec3> P, L;
    const glm::vec3 light(0.3f, 1.5f, 0.2f);
    for (int i = 0; i < 64; ++i) {
        glm::vec3 p(u(rng), -1.0f + 0.3f * std::abs(u(rng)), u(rng));
        if (glm::length(glm::vec2(p.x - light.x, p.z - light.z)) < 0.05f) continue;
        P.push_back(p);
        L.push_back(light);
    }
    auto res = runWalks(scene, P, L);
    int solved = 0;
    double worstM = 0, worstD = 0;
    for (size_t i = 0; i < P.size(); ++i) {
        glm::dvec2 foot(light.x, light.z), pp(P[i].x, P[i].z);
        double rho = glm::length(pp - foot);
        FlatSolution f = flatSnell(light.y, -P[i].y, rho, ior);
        glm::dvec2 m2 = foot + (pp - foot) / rho * f.x;
        glm::dvec3 M(m2.x, 0.0, m2.y);
        // Where the exact point lies outside the surface the walk must fail at the boundary.
        if (std::abs(M.x) > 1.999 || std::abs(M.z) > 1.999) continue;
        ASSERT_EQ(res[i].status, kSolved) << "walk " << i;
        ++solved;
        double dist = glm::length(glm::dvec3(light) - glm::dvec3(P[i]));
        worstM = std::max(worstM, glm::length(glm::dvec3(res[i].M) - M) / dist);
        worstD = std::max(worstD, std::abs(res[i].D - f.D) / f.D);
        if (ior == 1.0) {  // unfolded: D = (d_L + d_P)^2
            double dd = glm::length(glm::dvec3(light) - M) + glm::length(M - glm::dvec3(P[i]));
            EXPECT_NEAR(res[i].D / (dd * dd), 1.0, 1e-4) << "walk " << i;
        }
    }
    std::printf(
        "[ flat, ior %.2f ] %d walks solved; worst |M - M*| / |L - P| = %.2e, worst D "
        "relative error = %.2e\n",
        ior, solved, worstM, worstD);
    EXPECT_GT(solved, 40);
    EXPECT_LT(worstM, 1e-4);
    EXPECT_LT(worstD, 1e-4);
}

TEST(MNEEDimReduction, FlatWaterMatchesSnellAndTheClosedFormFocusing) {
    checkFlat(1.33);
}
TEST(MNEEDimReduction, FlatInterfaceWithEtaOneGivesTheUnfoldedDistance) {
    checkFlat(1.0);
}

// Reflection (beyond the paper): the flat mirror of tests/support/CausticScenes.h (a conductor
// square [-1, 1]^2 at y = 2 facing down) over receivers below it, a point light below the
// mirror. M is where P -> L' crosses the mirror, L' the light mirrored in it, and
// D = (d_P + d_L)^2 (the unfolded path).
TEST(MNEEDimReduction, FlatMirrorReflectsAtTheImageSource) {
    test::TempDir dir("loom-mnee-dr");
    auto scene = sceneFromJson(test::kMirrorScene, dir);
    const glm::vec3 light(0.3f, 1.0f, 0.0f), image(0.3f, 3.0f, 0.0f);
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-0.8f, 0.8f);
    std::vector<glm::vec3> P, L;
    for (int i = 0; i < 64; ++i) {
        P.push_back(glm::vec3(u(rng), 0.2f * std::abs(u(rng)), u(rng)));
        L.push_back(light);
    }
    auto res = runWalks(scene, P, L);
    int solved = 0, noStart = 0;
    for (size_t i = 0; i < P.size(); ++i) {
        float t = (2.0f - P[i].y) / (image.y - P[i].y);
        glm::vec3 expect = P[i] + t * (image - P[i]);
        if (std::abs(expect.x) > 0.98f || std::abs(expect.z) > 0.98f) continue;
        // The start point is where the line PL, beyond L, meets the mirror; where that line
        // misses it (while the reflection point is on it) there is no start.
        if (res[i].status == kNoStart) {
            ++noStart;
            continue;
        }
        ASSERT_EQ(res[i].status, kSolved) << "walk " << i;
        ++solved;
        EXPECT_LT(glm::length(res[i].M - expect), 1e-4f) << "walk " << i;
        double dd = glm::length(glm::dvec3(light) - glm::dvec3(expect)) +
                    glm::length(glm::dvec3(expect) - glm::dvec3(P[i]));
        EXPECT_NEAR(res[i].D / (dd * dd), 1.0, 1e-4) << "walk " << i;
    }
    std::printf(
        "[ flat mirror ] %d of %zu walks solved at the image source point, %d without a "
        "start point\n",
        solved, P.size(), noStart);
    EXPECT_GT(solved, 40);
}

// D against finite differences: move P by +-delta along two directions perpendicular to the
// beam, re-solve, and divide the area by the solid angle the light-side directions span.
// Returns the worst relative error over the walks whose four neighbours also solved.
double focusingFiniteDifferenceError(const std::string& kernel, int* checked) {
    test::TempDir dir("loom-mnee-dr");
    auto scene = sceneFromJson(
        waterScene("0.04 * sin(4 * x + 1) * cos(3 * y) + 0.02 * sin(7 * y)", 96, 1.33, kPointLight),
        dir);
    const glm::vec3 light(0.3f, 1.5f, 0.2f);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1.2f, 1.2f);
    std::vector<glm::vec3> base;
    for (int i = 0; i < 48; ++i) base.push_back(glm::vec3(u(rng), -1.0f, u(rng)));
    auto first =
        runWalks(scene, base, std::vector<glm::vec3>(base.size(), light), false, {}, 0, kernel);
    const float delta = 2e-3f;
    std::vector<glm::vec3> P;
    std::vector<size_t> which;
    for (size_t i = 0; i < base.size(); ++i) {
        if (first[i].status != kSolved) continue;
        glm::vec3 r = glm::normalize(base[i] - first[i].M);
        glm::vec3 e1 = glm::normalize(glm::cross(r, glm::vec3(1, 0, 0)));
        glm::vec3 e2 = glm::cross(r, e1);
        for (glm::vec3 e : {e1, -e1, e2, -e2}) P.push_back(base[i] + delta * e);
        which.push_back(i);
    }
    auto moved = runWalks(scene, P, std::vector<glm::vec3>(P.size(), light), false, {}, 0, kernel);
    double worst = 0;
    *checked = 0;
    for (size_t j = 0; j < which.size(); ++j) {
        const WalkOut* w = &moved[4 * j];
        bool ok = true;
        for (int k = 0; k < 4; ++k) ok = ok && w[k].status == kSolved;
        if (!ok) continue;
        auto dir = [&](int k) { return glm::dvec3(glm::normalize(w[k].M - light)); };
        glm::dvec3 d1 = (dir(0) - dir(1)) * 0.5, d2 = (dir(2) - dir(3)) * 0.5;
        double Dfd = double(delta) * delta / glm::length(glm::cross(d1, d2));
        double D = first[which[j]].D;
        worst = std::max(worst, std::abs(D - Dfd) / Dfd);
        ++*checked;
    }
    return worst;
}

TEST(MNEEDimReduction, FocusingFactorMatchesFiniteDifferencesOnAWavySurface) {
    int checked = 0;
    double err = focusingFiniteDifferenceError("passes/mnee_dr/tests/coplanar_walk.comp", &checked);
    std::printf("[ wavy ] D vs finite differences: %d points, worst relative error %.2e\n", checked,
                err);
    EXPECT_GT(checked, 30);
    // Central differences of float positions at delta = 2e-3 where D varies fast near the
    // focal points: the worst of 48 points measured 7.2e-3.
    EXPECT_LT(err, 2e-2);
    // The same with the normal's derivative left out of the ray differentials must fail.
    double biased =
        focusingFiniteDifferenceError("passes/mnee_dr/tests/coplanar_walk_biased.comp", &checked);
    std::printf("[ wavy, biased D ] worst relative error %.2e\n", biased);
    EXPECT_GT(biased, 5 * 2e-2);
}

// The Newton MNEE of the SMS pass (straight-line seed, half-vector constraints) on the same
// configurations: where both converge they find the same point.
TEST(MNEEDimReduction, AgreesWithNewtonMnee) {
    test::TempDir dir("loom-mnee-dr");
    auto scene =
        sceneFromJson(waterScene("0.05 * sin(5 * x + 2 * y) + 0.03 * sin(3 * y - 4 * x + 1)", 64,
                                 1.33, kPointLight),
                      dir);
    const glm::vec3 light(0.3f, 1.5f, 0.2f);
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> u(-1.5f, 1.5f);
    std::vector<glm::vec3> P, L;
    std::vector<std::vector<glm::vec4>> newtonCols;
    for (int i = 0; i < 256; ++i) {
        glm::vec3 p(u(rng), -1.0f, u(rng));
        P.push_back(p);
        L.push_back(light);
        // manifold_walk.comp rows: x0, ng0, y, ny, seed (w = 1: straight line, MNEE),
        // (constraint half-vector, iterations, threshold, max chain), es, et.
        newtonCols.push_back({glm::vec4(p, 0), glm::vec4(0, 1, 0, 0), glm::vec4(light, 0),
                              glm::vec4(0), glm::vec4(light, 1), glm::vec4(1, 20, 1e-5f, 1),
                              glm::vec4(1, 0, 0, 0), glm::vec4(0, 0, 1, 0)});
    }
    auto dr = runWalks(scene, P, L);
    auto newton = runColumns(scene, "passes/sms/tests/manifold_walk.comp", newtonCols, 8);
    int both = 0, same = 0, onlyDr = 0, onlyNewton = 0, neither = 0;
    int firstWay[8] = {}, otherWay[8] = {};  // how the coplanar walk ended where only Newton did
    int onlyNewtonStatus[8] = {}, onlyNewtonOther[8] = {};
    for (size_t i = 0; i < P.size(); ++i) {
        bool a = dr[i].status == kSolved, b = int(newton[i][0].x) == 3;  // TRIAL_CONVERGED
        if (a && b) {
            ++both;
            if (glm::length(dr[i].M - glm::vec3(newton[i][1])) < 1e-3f) ++same;
        } else if (a) {
            ++onlyDr;
        } else if (b) {
            ++onlyNewton;
            firstWay[dr[i].status]++;
            otherWay[dr[i].statusOther]++;
            onlyNewtonStatus[dr[i].status]++;
            onlyNewtonOther[dr[i].statusOther]++;
        } else {
            ++neither;
        }
    }
    std::printf(
        "[ vs Newton MNEE ] %zu queries: both %d (same point %d), only the coplanar walk "
        "%d, only Newton %d, neither %d\n",
        P.size(), both, same, onlyDr, onlyNewton, neither);
    std::printf(
        "  where only Newton converged, the coplanar walk's first / other direction ended: "
        "boundary %d / %d, cap %d / %d, total internal reflection %d / %d, degenerate %d / "
        "%d, no start %d\n",
        firstWay[kBoundary], otherWay[kBoundary], firstWay[kCap], otherWay[kCap], firstWay[kTir],
        otherWay[kTir], firstWay[kDegenerate], otherWay[kDegenerate], firstWay[kNoStart]);
    EXPECT_GE(both, 240);  // measured 256 of 256
    // A wavy surface can have several solutions; each method finds one of them.
    EXPECT_GE(same, int(0.95 * both));
}

// A solution beyond the mesh: the walk reaches a boundary edge and says so. Degenerate
// triangles and flipped normals: no hang, no NaN, every walk ends with a status.
TEST(MNEEDimReduction, MeshEdgeCasesEndCleanly) {
    test::TempDir dir("loom-mnee-dr");
    {
        auto scene = sceneFromJson(waterScene("0", 8, 1.33, kPointLight), dir);
        // Snell's point lies beyond the edge (x or z near 2.1, below the critical angle)
        // while the segment P -> L crosses the surface inside it.
        std::vector<glm::vec3> P = {glm::vec3(2.3f, -0.3f, 0.2f), glm::vec3(0.3f, -1.0f, 2.8f)};
        std::vector<glm::vec3> L(P.size(), glm::vec3(0.3f, 1.5f, 0.2f));
        // Start from the line P -> L: it crosses the surface inside, the solution is outside.
        // One direction runs into the edge; the other may end at total internal reflection.
        auto res = runWalks(scene, P, L);
        for (auto& r : res) {
            EXPECT_NE(r.status, kSolved);
            EXPECT_TRUE(r.status == kBoundary || r.statusOther == kBoundary)
                << r.status << " " << r.statusOther;
        }
    }
    {
        // A walk of several triangles (16 x 16 grid) under a cap of one ends at the cap.
        auto scene = sceneFromJson(waterScene("0", 16, 1.33, kPointLight), dir, "cap.json");
        std::vector<glm::vec3> P = {glm::vec3(-1.5f, -1.0f, -1.5f)},
                               L = {glm::vec3(0.3f, 1.5f, 0.2f)};
        auto free = runWalks(scene, P, L);
        ASSERT_EQ(free[0].status, kSolved);
        EXPECT_GT(free[0].triangles, 1);
        Settings capped;
        capped.maxTriangles = 1;
        auto c = runWalks(scene, P, L, false, capped);
        EXPECT_TRUE(c[0].status == kCap || c[0].statusOther == kCap) << c[0].status;
        EXPECT_NE(c[0].status, kSolved);
    }
    // A mesh with a repeated-index triangle and a zero-area (collinear) one over a wavy grid,
    // with its normals as they are and flipped.
    std::string obj;
    for (int j = 0; j <= 8; ++j)
        for (int i = 0; i <= 8; ++i) {
            float x = -2.0f + 0.5f * float(i), z = -2.0f + 0.5f * float(j);
            obj += "v " + std::to_string(x) + " " +
                   std::to_string(0.05f * std::sin(3 * x) * std::cos(2 * z)) + " " +
                   std::to_string(z) + "\n";
        }
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
            int a = 1 + j * 9 + i, b = a + 1, c = a + 9, d = c + 1;
            obj +=
                "f " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) + "\n";
            if (i == 3 && j == 3) continue;  // a hole: boundary edges inside the mesh
            obj +=
                "f " + std::to_string(a) + " " + std::to_string(d) + " " + std::to_string(b) + "\n";
        }
    obj += "f 41 41 42\nv 0.1 0.0 0.1\nv 0.2 0.0 0.2\nv 0.3 0.0 0.3\nf 82 83 84\n";
    std::ofstream(dir / "edge.obj") << obj;
    for (const char* flip : {"false", "true"}) {
        auto scene = sceneFromJson(
            casterScene(
                R"({"name": "water", "type": "mesh", "file": "edge.obj", "material": "water",
                            "caustic_caster": true, "flip_normals": )" +
                    std::string(flip) + "}",
                kPointLight),
            dir, std::string("edge_") + flip + ".json");
        std::mt19937 rng(21);
        std::uniform_real_distribution<float> u(-1.9f, 1.9f);
        std::vector<glm::vec3> P, L;
        for (int i = 0; i < 256; ++i) {
            P.push_back(glm::vec3(u(rng), -1.0f, u(rng)));
            L.push_back(glm::vec3(u(rng), 1.5f, u(rng)));
        }
        auto res = runWalks(scene, P, L);
        int counts[8] = {};
        for (auto& r : res) {
            ASSERT_GE(r.status, 0);
            ASSERT_LE(r.status, kNoRoot);
            counts[r.status]++;
            EXPECT_FALSE(std::isnan(r.M.x) || std::isnan(r.D) || std::isinf(r.D));
            EXPECT_LE(r.triangles, 1000);
        }
        std::printf(
            "[ edge mesh, flipped %s ] solved %d, no start %d, boundary %d, cap %d, TIR "
            "%d, degenerate %d, no root %d\n",
            flip, counts[0], counts[1], counts[2], counts[3], counts[4], counts[5], counts[6]);
        EXPECT_GT(counts[kSolved], 64);
        EXPECT_GT(counts[kBoundary], 0);
    }
}

// The special case of a closed curve inside the start triangle: one triangle at y = 0 whose
// vertex normals swirl, n_i ~ (0.1 - z_i, 1, x_i), with P below and L above the origin. With
// unnormalised normals N . (w x (M - P)) = 0.1 z - (x^2 + z^2), a circle of radius 0.05
// through the start point; the loader normalises vertex normals, which bends it a little,
// so the check is that the solution is on the conic of the normals as stored, away from the
// start point, without leaving the triangle. The walk must go round the closed curve inside
// the triangle and find the root of f on it.
TEST(MNEEDimReduction, EllipseInsideTheStartTriangle) {
    test::TempDir dir("loom-mnee-dr");
    const glm::vec3 V[3] = {{-0.6f, 0, -0.5f}, {0, 0, 0.6f}, {0.6f, 0, -0.5f}};
    glm::vec3 n[3];
    std::string obj;
    for (int i = 0; i < 3; ++i) {
        obj += "v " + std::to_string(V[i].x) + " 0 " + std::to_string(V[i].z) + "\n";
        n[i] = glm::normalize(glm::vec3(0.1f - V[i].z, 1.0f, V[i].x));
    }
    for (int i = 0; i < 3; ++i)
        obj += "vn " + std::to_string(n[i].x) + " " + std::to_string(n[i].y) + " " +
               std::to_string(n[i].z) + "\n";
    obj += "f 1//1 2//2 3//3\n";
    std::ofstream(dir / "swirl.obj") << obj;
    auto scene = sceneFromJson(
        casterScene(
            R"({"name": "swirl", "type": "mesh", "file": "swirl.obj", "material": "water", "caustic_caster": true})",
            R"({"type": "point", "position": [0, 1, 0], "intensity": 1, "caustic_emitter": true})"),
        dir);
    std::vector<glm::vec3> P, L;
    for (float h : {1.0f, 0.5f, 2.0f}) {
        P.push_back(glm::vec3(0, -h, 0));
        L.push_back(glm::vec3(0, 1, 0));
    }
    auto res = runWalks(scene, P, L);
    for (size_t i = 0; i < res.size(); ++i) {
        const WalkOut& r = res[i];
        std::printf(
            "[ swirl ] P depth %.1f: status %d, triangles %d, bisections %d, M (%.5f, %.5f, "
            "%.5f), sine %.1e\n",
            -P[i].y, r.status, r.triangles, r.bisections, r.M.x, r.M.y, r.M.z, r.sine);
        ASSERT_EQ(r.status, kSolved) << "walk " << i;
        EXPECT_EQ(r.prim, 2);       // the floor's two triangles come first
        EXPECT_LE(r.triangles, 2);  // never left the start triangle (one or both directions)
        glm::vec3 N = (1 - r.bary.x - r.bary.y) * n[0] + r.bary.x * n[1] + r.bary.y * n[2];
        glm::vec3 w(0, 1, 0);
        EXPECT_NEAR(glm::dot(N, glm::cross(w, r.M - P[i])), 0.0f, 1e-5f);
        EXPECT_GT(glm::length(r.M), 1e-3f);  // not the start point
        EXPECT_LT(glm::length(r.M), 0.2f);   // on the small closed curve
        EXPECT_LT(r.sine, 1e-3f);
    }
}

// An animated surface: the heightfield formula reads t, the scene re-tessellates it per frame
// and the walk runs on this frame's triangles (a flat surface moving up: y = 0.1 t).
TEST(MNEEDimReduction, AnimatedSurfaceIsWalkedAtTheFrameTime) {
    test::TempDir dir("loom-mnee-dr");
    auto scene = sceneFromJson(waterScene("0.05 * t", 8, 1.0, kPointLight), dir);
    ASSERT_TRUE(bool(scene.shapes[1].deformation));
    std::vector<glm::vec3> P = {glm::vec3(-0.5f, -1.0f, 0.4f)};
    std::vector<glm::vec3> L = {glm::vec3(0.3f, 1.5f, 0.2f)};
    for (float t : {0.0f, 4.0f}) {
        auto r = runWalks(scene, P, L, false, {}, t);
        ASSERT_EQ(r[0].status, kSolved);
        // Object height 0.05 t, scaled by 2: the surface is at y = 0.1 t.
        EXPECT_NEAR(r[0].M.y, 0.1f * t, 1e-4f) << "t = " << t;
    }
}

// The pass on the flat pool (tests/support/PoolCaustic.h) against the closed-form caustic.
const json kMneeDrPass = {{"name", "mnee"}, {"type", "MNEEDimReduction"}};

TEST(MNEEDimReduction, PoolUnderPointLightMatchesClosedForm) {
    test::expectPoolPointClosedForm(kMneeDrPass, 16, "mnee_dr");
}

TEST(MNEEDimReduction, PoolUnderDirectionalLightMatchesClosedForm) {
    test::expectPoolDirectionalClosedForm(kMneeDrPass, 8, "mnee_dr");
}

// A wavy water sheet under a small area light, seen from below (the floor is the primary
// hit): the caustic against unbiased SMS (every solution) and the full image against the
// reference path tracer, luminance on 2 x 2 regions. MNEE finds one solution per point, so it
// may miss energy where the waves fold the caustic; the test reports that fraction per region
// and requires it below the bound stated there.
std::string wavyPoolScene() {
    return R"J({
      "loom_scene": 1,
      "camera": {"origin": [0, 0.6, 1.0], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
      "materials": {"water": {"type": "dielectric", "ior": 1.33},
                    "floor": {"type": "diffuse", "reflectance": 0.5},
                    "lamp": {"type": "diffuse", "reflectance": 0}},
      "shapes": [
        {"name": "floor", "type": "rectangle", "material": "floor", "caustic_receiver": true,
         "transform": [{"scale": 4}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}]},
        {"name": "water", "type": "heightfield", "resolution": 96, "material": "water", "caustic_caster": true,
         "height": "0.015 * sin(9 * x + 3 * y) + 0.01 * sin(7 * y - 5 * x + 1)",
         "transform": [{"scale": [2, 2, 2]}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"translate": [0, 1, 0]}]},
        {"name": "lamp", "type": "rectangle", "material": "lamp", "emission": 60, "caustic_emitter": true,
         "transform": [{"scale": 0.12}, {"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0.1, 2.2, -0.2]}]}]
    })J";
}

struct WavyPoolRun {
    test::RegionStats color{2}, caustic{2};
};

WavyPoolRun runMneeDr(const scene::Scene& scene, const json& params, int frames) {
    json g = {{"passes", {{{"name", "mnee"}, {"type", "MNEEDimReduction"}, {"params", params}}}},
              {"edges", json::array()},
              {"outputs", {"mnee.color", "mnee.caustic"}}};
    auto s = test::frameStats(RenderGraph::parse(g.dump(), "<test>"), scene,
                              {"mnee.color", "mnee.caustic"}, frames, 2, 32, 11);
    return {s[0], s[1]};
}

// The caustic of unbiased SMS (single scattering) at primary receivers, `frames` frames.
test::RegionStats unbiasedSmsCaustic(const scene::Scene& scene, int frames) {
    json g = {
        {"passes",
         {{{"name", "sms"}, {"type", "SpecularManifoldSampling"}, {"params", {{"maxChain", 1}}}}}},
        {"edges", json::array()},
        {"outputs", {"sms.caustic"}}};
    return test::frameStats(RenderGraph::parse(g.dump(), "<test>"), scene, {"sms.caustic"}, frames,
                            2, 32, 29)[0];
}

// MNEE's caustic against unbiased SMS's per region: never more energy than every solution
// together (3 standard errors); returns the worst energy missed beyond 3 standard errors,
// as a fraction, and prints each region's.
double missedEnergy(const char* what, const test::RegionStats& mnee, const test::RegionStats& sms) {
    double worst = 0;
    for (int i = 0; i < 4; ++i) {
        double a = mnee.mean(i * 3), b = sms.mean(i * 3);
        double se = std::sqrt(mnee.stderr2(i * 3) + sms.stderr2(i * 3));
        std::printf(
            "%s region %d: caustic mnee_dr %.5f +- %.5f, unbiased sms %.5f +- %.5f "
            "(missed %.1f%% +- %.1f%%)\n",
            what, i, a, std::sqrt(mnee.stderr2(i * 3)), b, std::sqrt(sms.stderr2(i * 3)),
            100 * (b - a) / b, 100 * se / b);
        EXPECT_LT(a - b, 3 * se) << what << " region " << i;
        worst = std::max(worst, (b - a - 3 * se) / b);
    }
    return worst;
}

TEST(MNEEDimReduction, WavyPoolAgainstUnbiasedSmsAndThePathTracer) {
    test::TempDir dir("loom-mnee-dr");
    auto scene = sceneFromJson(wavyPoolScene(), dir);
    auto dr = runMneeDr(scene, json::object(), 128);
    auto sms = unbiasedSmsCaustic(scene, 128);
    auto pt = test::frameStats(test::ptGraph(32, 9), scene, {"pt.color"}, 64, 2, 32, 23)[0];
    double worstMissed = missedEnergy("wavy pool", dr.caustic, sms);
    for (int i = 0; i < 4; ++i)
        std::printf("region %d: full image %.5f +- %.5f vs path tracer %.5f +- %.5f\n", i,
                    dr.color.mean(i * 3), std::sqrt(dr.color.stderr2(i * 3)), pt.mean(i * 3),
                    std::sqrt(pt.stderr2(i * 3)));
    // Gentle waves: a second solution is rare; the energy missed stays below 5%.
    EXPECT_LT(worstMissed, 0.05);
    double z = test::maxZ(dr.color, pt);
    std::printf("full image vs path tracer: worst |z| %.2f\n", z);
    // The path tracer part is exact and the caustic misses at most the few percent above; the
    // path tracer's standard error is several times that, so the full image agrees within it.
    EXPECT_LT(z, 3.0);
}

// The project's pool (scenes/water_pool.json: the sun through a wavy heightfield), seen from
// under water so that the pool's floor and walls are primary receivers for SMS: the caustic
// against unbiased SMS per 2 x 2 region, the energy MNEE misses reported and bounded. The
// sun is a delta light, so the path tracer cannot see this caustic at all.
TEST(MNEEDimReduction, ProjectPoolFromUnderWaterAgainstUnbiasedSms) {
    auto scene = scene::loadScene(test::sourcePath("scenes/water_pool.json"));
    scene.camera.path.clear();
    scene.camera.toWorld = scene::lookAtMatrix(glm::vec3(0.2f, 0.45f, 0.85f),
                                               glm::vec3(-0.2f, 0.1f, -0.6f), glm::vec3(0, 1, 0));
    scene.camera.fov = 60.0f;
    scene.camera.fovAxis = scene::Camera::FovAxis::Y;
    // Receivers seen directly and through the water surface (from below, by reflection): both
    // estimators at receiverDepth 2, each with its own specular prefix (MNEE's traced on a
    // stream of its own, SMS's the path tracer's).
    auto dr = runMneeDr(scene, json::object(), 16);
    auto sms = unbiasedSmsCaustic(scene, 64);
    double worstMissed = missedEnergy("project pool", dr.caustic, sms);
    EXPECT_LT(worstMissed, 0.05);
}

// The shared water-caustic scene (Mitsuba 0.5, no caustic tags: tagged here — the wavy water
// top Mesh001 casts, every diffuse shape receives, the ceiling light emits): the full image
// against the reference path tracer, which finds this caustic only through BSDF sampling of a
// small light (large standard errors). Here MNEE's one solution per point is a large bias:
// floor points under this water (IOR 1.8, strong waves) have 4 to 15 distinct solutions
// (DISABLED_WaterCausticWalksAgainstNewton), and at 16x the frames the path tracer reads 2.5
// standard errors above MNEE in three regions (60-95 % of the energy missed). So the check is
// the known bias's direction: never brighter than the path tracer; the missed share is
// printed. Skips without ../shared/scenes.
TEST(MNEEDimReduction, SharedWaterCausticAgainstThePathTracer) {
    const std::string file =
        std::string(LOOM_SOURCE_DIR) + "/../shared/scenes/water-caustic/scene.xml";
    if (!std::filesystem::exists(file)) GTEST_SKIP() << "no " << file;
    auto scene = scene::loadScene(file);
    for (auto& shape : scene.shapes) {
        const auto& m = scene.materials[size_t(shape.material)];
        if (shape.name == "Mesh001")
            shape.flags |= scene::kCausticCasterRefract;
        else if (glm::length(shape.emission) > 0)
            shape.flags |= scene::kCausticEmitter;
        else if (m.type == scene::BsdfType::Diffuse)
            shape.flags |= scene::kCausticReceiver;
    }
    // LOOM_WATER_CAUSTIC_SCALE=k runs k times the frames (the README's numbers: k = 16).
    int k = std::getenv("LOOM_WATER_CAUSTIC_SCALE")
                ? std::atoi(std::getenv("LOOM_WATER_CAUSTIC_SCALE"))
                : 1;
    auto dr = runMneeDr(scene, json::object(), 64 * k);
    auto pt = test::frameStats(test::ptGraph(64, 9), scene, {"pt.color"}, 64 * k, 2, 32, 23)[0];
    for (int i = 0; i < 4; ++i) {
        double a = dr.color.mean(i * 3), b = pt.mean(i * 3);
        double se = std::sqrt(dr.color.stderr2(i * 3) + pt.stderr2(i * 3));
        std::printf(
            "water-caustic region %d: mnee_dr %.4f +- %.4f (caustic %.4f), path tracer "
            "%.4f +- %.4f: missed %.0f%% +- %.0f%%\n",
            i, a, std::sqrt(dr.color.stderr2(i * 3)), dr.caustic.mean(i * 3), b,
            std::sqrt(pt.stderr2(i * 3)), 100 * (b - a) / b, 100 * se / b);
        EXPECT_LT(a - b, 3 * se) << "region " << i;
    }
}

// Diagnostic (disabled: it asserts nothing yet) for the shared water-caustic scene, where the
// pass reads far below the path tracer under the water: floor points under the wavy water top
// against points of the ceiling light, the coplanar walk beside the Newton MNEE walk, and how
// each walk ended. Measured (512 queries): the coplanar walk solves 234 (Newton converges on
// 108 of them), ends at the mesh boundary on 155 (Newton finds 39) and at total internal
// reflection on 123 (Newton finds 18); Newton alone solves 165.
TEST(MNEEDimReduction, DISABLED_WaterCausticWalksAgainstNewton) {
    const std::string file =
        std::string(LOOM_SOURCE_DIR) + "/../shared/scenes/water-caustic/scene.xml";
    if (!std::filesystem::exists(file)) GTEST_SKIP() << "no " << file;
    auto scene = scene::loadScene(file);
    for (auto& shape : scene.shapes)
        if (shape.name == "Mesh001") shape.flags |= scene::kCausticCasterRefract;
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<glm::vec3> P, L;
    std::vector<std::vector<glm::vec4>> newtonCols;
    for (int i = 0; i < 512; ++i) {
        glm::vec3 p(0.9f * u(rng), 1e-3f, 0.15f + 0.75f * u(rng));
        glm::vec3 l(0.2f * u(rng), 1.98f, 0.2f * u(rng));
        P.push_back(p);
        L.push_back(l);
        newtonCols.push_back({glm::vec4(p, 0), glm::vec4(0, 1, 0, 0), glm::vec4(l, 0),
                              glm::vec4(0, -1, 0, 0), glm::vec4(l, 1), glm::vec4(1, 20, 1e-5f, 1),
                              glm::vec4(1, 0, 0, 0), glm::vec4(0, 0, 1, 0)});
    }
    auto dr = runWalks(scene, P, L);
    auto newton = runColumns(scene, "passes/sms/tests/manifold_walk.comp", newtonCols, 8);
    int status[8][2] = {};
    for (size_t i = 0; i < P.size(); ++i) status[dr[i].status][int(newton[i][0].x) == 3 ? 1 : 0]++;
    const char* names[] = {"solved", "no start", "boundary", "cap", "TIR", "degenerate", "no root"};
    for (int k = 0; k < 7; ++k)
        std::printf("coplanar walk %-10s: Newton converged %3d, failed %3d\n", names[k],
                    status[k][1], status[k][0]);
    // Solutions per floor point: Newton walks from 256 seeds spread over the water top (SMS
    // seeding), the converged points clustered at 1e-3.
    for (int q = 0; q < 8; ++q) {
        std::vector<std::vector<glm::vec4>> cols;
        for (int k = 0; k < 256; ++k) {
            glm::vec3 seed(u(rng), 1.5f, -0.65f + 0.825f * (u(rng) + 1));
            cols.push_back({glm::vec4(P[q], 0), glm::vec4(0, 1, 0, 0), glm::vec4(L[q], 0),
                            glm::vec4(0, -1, 0, 0), glm::vec4(seed, 0), glm::vec4(1, 20, 1e-5f, 1),
                            glm::vec4(1, 0, 0, 0), glm::vec4(0, 0, 1, 0)});
        }
        auto out = runColumns(scene, "passes/sms/tests/manifold_walk.comp", cols, 8);
        std::vector<glm::vec3> unique;
        for (auto& o : out) {
            if (int(o[0].x) != 3) continue;
            glm::vec3 m(o[1]);
            bool seen = false;
            for (auto& v : unique) seen = seen || glm::length(v - m) < 1e-3f;
            if (!seen) unique.push_back(m);
        }
        std::printf(
            "floor point %d: %zu distinct solutions from 256 seeds; the coplanar walk: %s\n", q,
            unique.size(), names[dr[size_t(q)].status]);
    }
}

// Bad input: missing tags, an out-of-range parameter and an animated height formula that
// becomes non-finite at a later frame are each one named error, not a black caustic.
TEST(MNEEDimReduction, BadInputIsANamedError) {
    test::TempDir dir("loom-mnee-dr-bad");
    auto render = [&](const std::string& sceneText, const json& params, float time) {
        auto scene = sceneFromJson(sceneText, dir);
        json g = {
            {"passes", {{{"name", "mnee"}, {"type", "MNEEDimReduction"}, {"params", params}}}},
            {"edges", json::array()},
            {"outputs", {"mnee.color"}}};
        Renderer r(test::gpuContext(), RenderGraph::parse(g.dump(), "<test>"), 8, 8, 1);
        r.setScene(scene);
        r.setTime(time);
        r.frame();
    };
    auto expectError = [&](const std::string& sceneText, const json& params, float time,
                           const std::string& what) {
        try {
            render(sceneText, params, time);
            FAIL() << "should fail: " << what;
        } catch (const UserError& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    std::string good = waterScene("0.05 * sin(3 * x)", 8, 1.33, kPointLight);
    auto edit = [](std::string text, const std::string& from, const std::string& to) {
        text.replace(text.find(from), from.size(), to);
        return text;
    };
    expectError(edit(good, "\"caustic_receiver\": true,", ""), json::object(), 0,
                "no caustic receivers");
    expectError(edit(good, "\"caustic_caster\": true,", ""), json::object(), 0,
                "no caustic casters");
    expectError(edit(good, ", \"caustic_emitter\": true", ""), json::object(), 0,
                "no caustic emitters");
    expectError(good, {{"maxBisections", 0}}, 0, "maxBisections");
    expectError(waterScene("0.05 * log(4 - t)", 8, 1.33, kPointLight), json::object(), 6,
                "not finite");
}

// The comparison above sees double counting: with the covered paths left in the path part,
// the full image is too bright.
TEST(MNEEDimReduction, DoubleCountingIsDetected) {
    test::TempDir dir("loom-mnee-dr");
    auto scene = sceneFromJson(wavyPoolScene(), dir);
    auto dr = runMneeDr(scene, {{"excludeCovered", false}}, 64);
    auto pt = test::frameStats(test::ptGraph(32, 9), scene, {"pt.color"}, 64, 2, 32, 23)[0];
    double a = 0, b = 0;
    double z = test::maxZ(dr.color, pt, &a, &b);
    std::printf("double counting: worst |z| %.1f (mnee_dr %.5f, pt %.5f)\n", z, a, b);
    EXPECT_GT(z, 6.0);
    EXPECT_GT(a, b);
}

}  // namespace
}  // namespace loom
