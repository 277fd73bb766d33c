// SurfacePoint's differential geometry (shaders/lib/scene.glsl surface_point, through
// tests/data/surface_point.comp on lavapipe): dp/du, dp/dv, dn/du, dn/dv in the barycentric
// parameterisation, against central differences of position and shading normal on a coarse
// sphere mesh with interpolated vertex normals (curved triangles: the normalization matters).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>

#include "core/graph/Renderer.h"
#include "core/scene/Camera.h"
#include "core/scene/Shapes.h"
#include "tests/support/GpuSupport.h"

using namespace loom;
using namespace loom::scene;

namespace {

constexpr uint32_t kPoints = 2048;
constexpr uint32_t kStride = 12;  // vec4 per point, see surface_point.comp
constexpr float kStep = 0.05f;    // barycentric step of the central differences
constexpr double kEps = 0x1p-24;  // float unit roundoff

Scene sphereScene() {
    Scene s;
    s.sourceFile = "<surface point>";
    // 30 degrees between neighbouring vertex normals: dn/du ~ 0.5, normalization term ~ 0.1.
    s.meshes.push_back(makeSphere(6, 12));
    s.materials.push_back(Material{});
    Shape sphere;
    sphere.name = "sphere";
    sphere.mesh = 0;
    sphere.material = 0;
    s.shapes.push_back(sphere);
    Light env;
    env.type = LightType::Constant;
    s.lights.push_back(env);
    s.camera.toWorld = lookAtMatrix({0, 0, 4}, {0, 0, 0}, {0, 1, 0});
    return s;
}

glm::dvec3 vec(const float* p) {
    return {p[0], p[1], p[2]};
}

// The shading normal of surface_point in double precision.
glm::dvec3 shadingNormal(const glm::dvec3 n[3], double u, double v) {
    return glm::normalize((1.0 - u - v) * n[0] + u * n[1] + v * n[2]);
}

// Central difference of the normal along barycentric direction e with step h.
glm::dvec3 normalDifference(const glm::dvec3 n[3], glm::dvec2 b, glm::dvec2 e, double h) {
    glm::dvec2 p = b + h * e, m = b - h * e;
    return (shadingNormal(n, p.x, p.y) - shadingNormal(n, m.x, m.y)) / (2.0 * h);
}

double maxAbs(glm::dvec3 a) {
    return std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z)});
}

}  // namespace

// Positions are linear in (u, v): the differences equal dp/du = p1 - p0 up to rounding. Normals
// are not: the tolerance is the central difference's truncation error at this step, measured
// in double precision against a 100x smaller step (whose own error is 1e-4 times smaller),
// plus float rounding of the differenced normals (a few ulps each, divided by the step 2h).
TEST(SurfacePoint, PartialsMatchCentralDifferences) {
    json g = {
        {"name", "surface_point"},
        {"passes",
         {{{"name", "k"},
           {"type", "ComputePass"},
           {"params",
            {{"shader", std::string(LOOM_TEST_DATA) + "/surface_point.comp"},
             {"outputs",
              {{"results",
                {{"glsl", "Results"}, {"kind", "buffer"}, {"bytes", kPoints * kStride * 16}}}}},
             {"constants",
              {{"count", {{"type", "uint"}, {"default", kPoints}}},
               {"seed", {{"type", "uint"}, {"default", 3}}},
               {"h", {{"type", "float"}, {"default", kStep}}}}},
             {"dispatch", {kPoints, 1, 1}}}}}}},
        {"edges", json::array()},
        {"outputs", {"k.results"}}};
    Renderer r(test::gpuContext(), RenderGraph::parse(g.dump(), "<test>"), 8, 8, 1);
    r.setScene(sphereScene());
    r.frame();
    std::vector<float> out(kPoints * kStride * 4);
    r.gpu().downloadBuffer(*r.graph().outputBuffer("k.results"), out.data(), out.size() * 4);

    const double h = kStep;
    const double roundoff = 16.0 * kEps / h;  // |n| = 1: a few ulps per component, over 2h
    double worstP = 0, worstN = 0, worstTrunc = 0, worstExact = 0, worstRatio = 0;
    int detected = 0, bad = 0;
    // Counts failures, reporting the first few (a wrong formula fails at every point).
    auto check = [&](bool ok, const std::string& what) {
        if (!ok && ++bad <= 5) ADD_FAILURE() << what;
    };
    for (uint32_t i = 0; i < kPoints; ++i) {
        const float* rec = &out[size_t(i) * kStride * 4];
        auto at = [&](int k) { return vec(rec + 4 * k); };
        const glm::dvec2 b(rec[0], rec[1]);
        const glm::dvec3 n[3] = {at(9), at(10), at(11)};
        const std::string where =
            " at point " + std::to_string(i) + " of triangle " + std::to_string(int(rec[2]));

        // Positions: exact up to rounding of |p| <= 1 over the step.
        for (int k = 0; k < 2; ++k) {
            double err = maxAbs(at(5 + k) - at(1 + k));
            worstP = std::max(worstP, err);
            check(err < roundoff,
                  (k == 0 ? "dp/du" : "dp/dv") + where + ": " + std::to_string(err));
        }
        // Normals.
        for (int k = 0; k < 2; ++k) {
            const glm::dvec2 e = k == 0 ? glm::dvec2(1, 0) : glm::dvec2(0, 1);
            const glm::dvec3 ref = normalDifference(n, b, e, h / 100.0);
            const double trunc = maxAbs(normalDifference(n, b, e, h) - ref);
            const glm::dvec3 analytic = at(3 + k), fd = at(7 + k);
            const double tol = trunc + roundoff + 8.0 * kEps * maxAbs(analytic);
            const double err = maxAbs(fd - analytic);
            worstN = std::max(worstN, err);
            worstTrunc = std::max(worstTrunc, trunc);
            worstRatio = std::max(worstRatio, err / tol);
            const std::string name = k == 0 ? "dn/du" : "dn/dv";
            check(err < tol, name + " vs central differences" + where + ": " + std::to_string(err) +
                                 " > " + std::to_string(tol));
            // The analytic partial itself, against the double-precision derivative.
            const double exactErr = maxAbs(analytic - ref);
            worstExact = std::max(worstExact, exactErr);
            check(exactErr < 1e-5,
                  name + " vs double precision" + where + ": " + std::to_string(exactErr));

            // Would the test notice dn/du without the normalization term, (n1 - n0) / |n|?
            const glm::dvec3 raw = (k == 0 ? n[1] : n[2]) - n[0];
            const double len = glm::length((1.0 - b.x - b.y) * n[0] + b.x * n[1] + b.y * n[2]);
            if (maxAbs(raw / len - fd) > tol) ++detected;
        }
    }
    std::printf(
        "SurfacePoint: worst |dp fd - dp| %.3g, |dn fd - dn| %.3g (truncation bound up to "
        "%.3g, worst error/tolerance %.3f), |dn - double| %.3g; a dropped normalization "
        "term is caught at %d of %u partials\n",
        worstP, worstN, worstTrunc, worstRatio, worstExact, detected, 2 * kPoints);
    EXPECT_EQ(bad, 0);
    EXPECT_GT(detected, int(0.9 * 2 * kPoints)) << "tolerance too loose to catch the bug class";
}
