// SurfacePoint's differential geometry (shaders/lib/scene.glsl surface_point, through
// tests/data/surface_point.comp on lavapipe): dp/du, dp/dv, dn/du, dn/dv in the barycentric
// parameterisation, against central differences of position and shading normal on a coarse
// sphere mesh with interpolated vertex normals (curved triangles: the normalization matters).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <random>

#include "core/graph/Renderer.h"
#include "core/scene/Camera.h"
#include "core/scene/Shapes.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/KernelColumns.h"

using namespace loom;
using namespace loom::scene;

namespace {

constexpr uint32_t kPoints = 2048;
constexpr uint32_t kStride = 12;  // vec4 per point, see surface_point.comp
constexpr float kStep = 0.05f;    // barycentric step of the central differences
constexpr double kEps = 0x1p-24;  // float unit roundoff

// One shape (mesh, material) under a constant environment, the camera on +z.
Scene oneShapeScene(Mesh mesh, const Material& material) {
    Scene s;
    s.sourceFile = "<surface point>";
    s.meshes.push_back(std::move(mesh));
    s.materials.push_back(material);
    Shape shape;
    shape.name = "shape";
    shape.mesh = 0;
    shape.material = 0;
    s.shapes.push_back(shape);
    Light env;
    env.type = LightType::Constant;
    s.lights.push_back(env);
    s.camera.toWorld = lookAtMatrix({0, 0, 4}, {0, 0, 0}, {0, 1, 0});
    return s;
}

Scene sphereScene() {
    // 30 degrees between neighbouring vertex normals: dn/du ~ 0.5, normalization term ~ 0.1.
    return oneShapeScene(makeSphere(6, 12), Material{});
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

// Normal maps (shaders/lib/shading.glsl), read as normals (2 rgb - 1, bilinear) or as slopes
// (use_slopes, the SMS normalmap: each texel's normalised normal as (x / z, y / z, 1), bilinear),
// against the same lookup written here in double from the texels: wrap-around bilinear cells
// with texel centres at (i + 0.5) / size, the tangent frame of the interpolated normal. A 4 x 4
// map of normals tilted up to 60 degrees, 512 random points on a rectangle, both modes; each
// mode must also differ from the other (so that the comparison can tell them apart).
TEST(ShadingPoint, NormalMapsMatchTheirTexelsAsNormalsOrSlopes) {
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    Texture map;
    map.name = "tilted";
    map.width = map.height = 4;
    map.isNormalMap = true;
    map.uvScale = glm::vec2(1.5f, 1.0f);
    for (int i = 0; i < 16; ++i) {
        double tilt = 1.05 * u01(rng), phi = 2 * M_PI * u01(rng);
        glm::dvec3 n(std::sin(tilt) * std::cos(phi), std::sin(tilt) * std::sin(phi),
                     std::cos(tilt));
        for (int c = 0; c < 3; ++c) map.rgba.push_back(float(0.5 * (n[c] + 1)));
        map.rgba.push_back(1.0f);
    }
    auto texel = [&](int x, int y) {
        x = (x % 4 + 4) % 4;
        y = (y % 4 + 4) % 4;
        const float* p = &map.rgba[size_t(4 * (y * 4 + x))];
        return 2.0 * glm::dvec3(p[0], p[1], p[2]) - 1.0;
    };
    auto expected = [&](bool slopes, glm::dvec2 uv, glm::dvec3 t, glm::dvec3 b, glm::dvec3 n) {
        glm::dvec2 st = (glm::fract(uv * glm::dvec2(map.uvScale)) * 4.0) - 0.5;
        glm::dvec2 i0 = glm::floor(st), w = st - i0;
        glm::dvec3 nt(0.0);
        for (int k = 0; k < 4; ++k) {
            int dx = k & 1, dy = k >> 1;
            glm::dvec3 v = texel(int(i0.x) + dx, int(i0.y) + dy);
            if (slopes) {
                v = glm::normalize(v);
                v = glm::dvec3(v.x / v.z, v.y / v.z, 1.0);
            }
            nt += (dx ? w.x : 1 - w.x) * (dy ? w.y : 1 - w.y) * v;
        }
        return glm::normalize(nt.x * t + nt.y * b + nt.z * n);
    };
    std::vector<std::vector<glm::vec4>> cols;
    for (int i = 0; i < 512; ++i) {
        double a = u01(rng), c = u01(rng);
        if (a + c > 1) a = 1 - a, c = 1 - c;
        cols.push_back({glm::vec4(float(i % 2), float(a), float(c), 0.0f)});
    }
    double worst[2] = {0, 0}, apart[2] = {0, 0};
    for (bool slopes : {false, true}) {
        Material m;
        m.normalMap = 0;
        m.normalMapUseSlopes = slopes;
        Scene s = oneShapeScene(makeRectangle(), m);
        s.textures.push_back(map);
        auto out = test::runColumns(s, "tests/data/shading_normal.comp", cols, 5);
        for (size_t i = 0; i < cols.size(); ++i) {
            auto at = [&](int row) { return glm::dvec3(glm::vec3(out[i][row])); };
            glm::dvec2 uv(out[i][1].x, out[i][1].y);
            glm::dvec3 want = expected(slopes, uv, at(2), at(3), at(4));
            glm::dvec3 other = expected(!slopes, uv, at(2), at(3), at(4));
            worst[slopes] = std::max(worst[slopes], glm::length(at(0) - want));
            apart[slopes] = std::max(apart[slopes], glm::length(other - want));
        }
        EXPECT_LT(worst[slopes], 2e-5) << (slopes ? "slopes" : "normals");
        EXPECT_GT(apart[slopes], 0.05) << "the two modes cannot be told apart here";
    }
    std::printf(
        "normal maps: worst |n - expected| %.2g (normals), %.2g (slopes); the modes differ by up "
        "to %.2f\n",
        worst[0], worst[1], apart[1]);
}
