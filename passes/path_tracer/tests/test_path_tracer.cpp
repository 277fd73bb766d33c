// Statistical and analytic tests of the reference path tracer. Tolerances come from the
// measured standard error over independent frames (z-scores), never from a guessed epsilon.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <sstream>

#include "core/graph/Renderer.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneGpu.h"
#include "core/scene/SceneLoader.h"
#include "core/scene/Shapes.h"
#include "tests/support/RegionStats.h"
#include "tests/support/TestSupport.h"

using namespace loom;
using namespace loom::scene;
using loom::test::maxZ;
using loom::test::RegionStats;

namespace {

std::shared_ptr<gpu::Context> sharedGpu() {
    static std::shared_ptr<gpu::Context> gpu = [] {
        gpu::Context::Options o;
        o.cacheDir = (std::filesystem::temp_directory_path() / "loom-test-cache").string();
        return gpu::Context::create(o);
    }();
    return gpu;
}

std::unique_ptr<RenderGraph> ptGraph(const json& ptParams, bool withGBuffer = false) {
    json g = {{"name", "pt_test"},
              {"passes", {{{"name", "pt"}, {"type", "PathTracer"}, {"params", ptParams}}}},
              {"edges", json::array()},
              {"outputs", {"pt.color"}}};
    if (withGBuffer) {
        g["passes"].push_back({{"name", "gbuf"},
                               {"type", "GBuffer"},
                               {"params", {{"jitter", true}, {"motionBlur", false}}}});
        g["outputs"].push_back("gbuf.position");
        g["outputs"].push_back("gbuf.geoNormal");
    }
    return RenderGraph::parse(g.dump(), "<test>");
}

Camera lookAtCamera(glm::vec3 origin, glm::vec3 target, float fov) {
    Camera c;
    c.toWorld = lookAtMatrix(origin, target, glm::vec3(0, 1, 0));
    c.fov = fov;
    c.fovAxis = Camera::FovAxis::X;
    return c;
}

Scene furnaceScene(const Material& sphereMaterial, float envRadiance, float fov) {
    Scene s;
    s.sourceFile = "<furnace>";
    s.meshes.push_back(makeSphere(32, 64));
    s.materials.push_back(sphereMaterial);
    Shape sphere;
    sphere.name = "sphere";
    sphere.mesh = 0;
    sphere.material = 0;
    s.shapes.push_back(sphere);
    Light env;
    env.type = LightType::Constant;
    env.intensity = glm::vec3(envRadiance);
    s.lights.push_back(env);
    s.camera = lookAtCamera({0, 0, 4}, {0, 0, 0}, fov);
    return s;
}

}  // namespace

// Mean and standard error of channel 0 over all pixels of `frames` frames.
std::pair<double, double> meanAndStderr(Renderer& r, int frames) {
    double sum = 0, sum2 = 0;
    size_t n = 0;
    for (int f = 0; f < frames; ++f) {
        r.frame();
        ImageData img = r.readOutput("pt.color");
        for (uint32_t i = 0; i < img.width * img.height; ++i) {
            double v = img.pixels[i * 4];
            sum += v;
            sum2 += v * v;
            ++n;
        }
    }
    double mean = sum / n;
    return {mean, std::sqrt(std::max(sum2 / n - mean * mean, 0.0) / n)};
}

// White furnace: a convex sphere of albedo 1 in a uniform environment L is invisible — every
// pixel, sphere or background, has expectation L exactly, for every sampling strategy.
TEST(PathTracer, WhiteFurnaceDiffuseAlbedoOne) {
    Material m;
    m.reflectance = glm::vec3(1.0f);
    for (const char* strategy : {"mis", "bsdf", "nee"}) {
        Renderer r(sharedGpu(), ptGraph({{"strategy", strategy}, {"samplesPerPixel", 4}}), 24, 24);
        r.setScene(furnaceScene(m, 1.5f, 40.0f));
        auto [mean, se] = meanAndStderr(r, 6);
        EXPECT_NEAR(mean, 1.5, 4 * se + 1e-6) << strategy << " se " << se;
    }
}

// A convex sphere has no interreflection: with albedo rho it reflects rho * L. The camera is
// close enough that the sphere fills the frame.
TEST(PathTracer, FurnaceDiffuseAlbedo) {
    Material m;
    m.reflectance = glm::vec3(0.7f);
    Renderer r(sharedGpu(), ptGraph({{"samplesPerPixel", 4}}), 24, 24);
    r.setScene(furnaceScene(m, 2.0f, 16.0f));
    auto [mean, se] = meanAndStderr(r, 6);
    EXPECT_NEAR(mean, 1.4, 4 * se + 1e-6) << "se " << se;
}

// A smooth dielectric conserves energy: the sphere is invisible in the furnace (all paths
// escape eventually; Russian roulette keeps it unbiased).
TEST(PathTracer, WhiteFurnaceSmoothDielectric) {
    Material m;
    m.type = BsdfType::Dielectric;
    m.eta = 1.5f;
    Renderer r(sharedGpu(), ptGraph({{"samplesPerPixel", 4}, {"maxBounces", 64}}), 24, 24);
    r.setScene(furnaceScene(m, 1.0f, 16.0f));
    auto [mean, se] = meanAndStderr(r, 6);
    EXPECT_NEAR(mean, 1.0, 4 * se + 1e-6) << "se " << se;
}

// Rough dielectric: single-scattering microfacet models lose energy at grazing angles but
// must never create it; the loss at alpha = 0.1 is small.
TEST(PathTracer, FurnaceRoughDielectricNeverGainsEnergy) {
    Material m;
    m.type = BsdfType::RoughDielectric;
    m.eta = 1.5f;
    m.alpha = 0.1f;
    Renderer r(sharedGpu(), ptGraph({{"samplesPerPixel", 4}, {"maxBounces", 64}}), 24, 24);
    r.setScene(furnaceScene(m, 1.0f, 16.0f));
    auto [mean, se] = meanAndStderr(r, 6);
    EXPECT_LE(mean, 1.0 + 4 * se);
    EXPECT_GT(mean, 0.9) << "energy loss above 10% at alpha 0.1";
    std::printf("rough dielectric furnace (alpha 0.1): %.4f +- %.4f\n", mean, se);
}

// Delta lights over a diffuse plane, per pixel (direct lighting only; a delta light has no
// sampling noise, so each pixel is exact up to float rounding):
//   point:       L = albedo / pi * I cos(theta) / d^2           (inverse square, cosine)
//   spot:        the same times Mitsuba's falloff: 1 inside the beam width, linear in angle to
//                0 at the cutoff, 0 outside
//   directional: L = albedo / pi * E cos(theta)                 (E = irradiance normal to it)
TEST(PathTracer, DeltaLightsOverPlaneMatchAnalyticIrradiance) {
    Scene s;
    s.sourceFile = "<plane>";
    s.meshes.push_back(makeRectangle());
    Material m;
    m.reflectance = glm::vec3(0.6f, 0.5f, 0.4f);
    s.materials.push_back(m);
    Shape plane;
    plane.mesh = 0;
    plane.material = 0;
    // Rectangle is [-1,1]^2 in z=0 facing +z; scale it to 4x4 and lay it on y=0 facing +y.
    plane.toWorld = glm::rotate(glm::mat4(1.0f), glm::radians(-90.0f), glm::vec3(1, 0, 0)) *
                    glm::scale(glm::mat4(1.0f), glm::vec3(2.0f));
    s.shapes.push_back(plane);
    s.camera = lookAtCamera({0, 3, 2.5f}, {0, 0, 0}, 45.0f);

    Light point;
    point.type = LightType::Point;
    point.position = glm::vec3(0.3f, 1.0f, -0.2f);
    point.intensity = glm::vec3(2.0f, 3.0f, 4.0f);
    Light spot = point;
    spot.type = LightType::Spot;
    spot.position = glm::vec3(-0.2f, 1.5f, 0.1f);
    spot.direction = glm::normalize(glm::vec3(0.3f, -1.0f, -0.2f));
    spot.cutoffAngle = 35.0f;
    spot.beamWidth = 20.0f;
    Light directional;
    directional.type = LightType::Directional;
    directional.direction = glm::normalize(glm::vec3(0.4f, -1.0f, 0.3f));  // of travel
    directional.intensity = glm::vec3(1.5f, 1.0f, 0.5f);

    for (const Light& light : {point, spot, directional}) {
        s.lights = {light};
        Renderer r(
            sharedGpu(),
            ptGraph({{"maxBounces", 1}, {"motionBlur", false}, {"samplesPerPixel", 1}}, true), 32,
            32);
        r.setScene(s);
        r.frame();
        ImageData color = r.readOutput("pt.color");
        ImageData pos = r.readOutput("gbuf.position");
        int tested = 0, inBeam = 0, inFalloff = 0;
        for (uint32_t i = 0; i < color.width * color.height; ++i) {
            if (pos.pixels[i * 4 + 3] == 0.0f) continue;  // miss
            glm::dvec3 p(pos.pixels[i * 4], pos.pixels[i * 4 + 1], pos.pixels[i * 4 + 2]);
            glm::dvec3 E;
            if (light.type == LightType::Directional) {
                E = glm::dvec3(light.intensity) * std::max(0.0, -double(light.direction.y));
            } else {
                glm::dvec3 d = glm::dvec3(light.position) - p;
                double dist2 = glm::dot(d, d);
                E = glm::dvec3(light.intensity) * std::max(0.0, glm::normalize(d).y) / dist2;
                if (light.type == LightType::Spot) {
                    double angle = std::acos(std::clamp(
                        glm::dot(-glm::normalize(d), glm::dvec3(light.direction)), -1.0, 1.0));
                    double cutoff = glm::radians(double(light.cutoffAngle));
                    double beam = glm::radians(double(light.beamWidth));
                    double fall = angle >= cutoff ? 0.0
                                  : angle <= beam ? 1.0
                                                  : (cutoff - angle) / (cutoff - beam);
                    // Away from the cutoff and beam edges by float precision.
                    if (std::abs(angle - cutoff) < 1e-4 || std::abs(angle - beam) < 1e-4) continue;
                    inBeam += fall == 1.0;
                    inFalloff += fall > 0.0 && fall < 1.0;
                    E *= fall;
                }
            }
            for (int c = 0; c < 3; ++c) {
                double expected = m.reflectance[c] / M_PI * E[c];
                EXPECT_NEAR(color.pixels[i * 4 + c], expected, 1e-4 * expected + 1e-6)
                    << "light type " << int(light.type) << ", pixel " << i;
            }
            ++tested;
        }
        EXPECT_GT(tested, 500);
        if (light.type == LightType::Spot) {
            EXPECT_GT(inBeam, 20);
            EXPECT_GT(inFalloff, 20);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Ground truth that shares no code with Loom's light sampling.

using glm::dvec3;

// Irradiance at x (unit normal n) from a uniform Lambertian polygon of radiance L that emits
// from its front side only (the side of its winding normal), by Lambert's formula
// E = L/2 sum_i Theta_i (n . g_i): Theta_i is the angle the edge (v_i, v_{i+1}) subtends at x and
// g_i the unit normal of the plane through x and that edge (Arvo 1995, "Applications of
// Irradiance Tensors to the Simulation of Non-Lambertian Phenomena", Eq. 1). The polygon is
// first clipped to the hemisphere above x (Sutherland-Hodgman), where the formula holds.
double polygonIrradiance(dvec3 x, dvec3 n, const std::vector<dvec3>& poly, double L) {
    dvec3 nl = glm::cross(poly[1] - poly[0], poly[2] - poly[0]);
    if (glm::dot(nl, x - poly[0]) <= 0.0) return 0.0;  // behind the emitter
    std::vector<dvec3> c;
    for (size_t i = 0; i < poly.size(); ++i) {
        dvec3 a = poly[i] - x, b = poly[(i + 1) % poly.size()] - x;
        double da = glm::dot(n, a), db = glm::dot(n, b);
        if (da > 0.0) c.push_back(a);
        if ((da > 0.0) != (db > 0.0)) c.push_back(a + (b - a) * (da / (da - db)));
    }
    double sum = 0.0;
    for (size_t i = 0; i < c.size(); ++i) {
        dvec3 a = glm::normalize(c[i]), b = glm::normalize(c[(i + 1) % c.size()]);
        dvec3 g = glm::cross(a, b);
        double len = glm::length(g);
        if (len > 0.0) sum += std::atan2(len, glm::dot(a, b)) * glm::dot(n, g / len);
    }
    return 0.5 * L * std::abs(sum);
}

// The formula against two limits it must reproduce: a polygon covering nearly the whole
// hemisphere (E -> pi L) and a small distant one (E -> L A cos_x cos_l / d^2).
TEST(PathTracer, LambertPolygonFormulaLimits) {
    double big = 1e5;
    std::vector<dvec3> ceiling = {{-big, 1, -big}, {big, 1, -big}, {big, 1, big}, {-big, 1, big}};
    EXPECT_NEAR(polygonIrradiance({0, 0, 0}, {0, 1, 0}, ceiling, 2.0), 2.0 * M_PI, 1e-3);
    // 0.01 x 0.01 square at distance 10, tilted so that both cosines differ from 1.
    dvec3 c(3, 9, 0);
    double d = glm::length(c);
    dvec3 nl = glm::normalize(dvec3(0.3, -1, 0.2));
    dvec3 t = glm::normalize(glm::cross(nl, dvec3(0, 0, 1))), b = glm::cross(nl, t);
    std::vector<dvec3> small = {c - 0.005 * t - 0.005 * b, c - 0.005 * t + 0.005 * b,
                                c + 0.005 * t + 0.005 * b, c + 0.005 * t - 0.005 * b};
    if (glm::dot(glm::cross(small[1] - small[0], small[2] - small[0]), -c) < 0.0)
        std::reverse(small.begin(), small.end());
    double expected = 1e-4 * (c.y / d) * std::abs(glm::dot(nl, c / d)) / (d * d);
    EXPECT_NEAR(polygonIrradiance({0, 0, 0}, {0, 1, 0}, small, 1.0), expected, 1e-4 * expected);
    // Half the hemisphere clipped away: a vertical wall through x covers half of it (pi/2 L).
    std::vector<dvec3> wall = {{0, -big, -big}, {0, -big, big}, {0, big, big}, {0, big, -big}};
    if (glm::dot(glm::cross(wall[1] - wall[0], wall[2] - wall[0]), dvec3(1, 0, 0)) < 0.0)
        std::reverse(wall.begin(), wall.end());
    EXPECT_NEAR(polygonIrradiance({1e-9, 0, 0}, {0, 1, 0}, wall, 1.0), M_PI / 2, 1e-3);
}

namespace {

// A polygonal emitter of radiance L over a large diffuse floor (y = 0, albedo rho), seen by a
// camera; the emitter's reverse side is black.
struct PolygonCase {
    const char* name;
    std::vector<glm::vec3> polygon;  // counter-clockwise around the emitting side
    float radiance;
    glm::vec3 cameraOrigin, cameraTarget;
    float fov;
    bool bsdfFeasible;  // BSDF sampling hits the emitter often enough to be tested
};

constexpr float kFloorAlbedo = 0.8f;

Scene polygonScene(const PolygonCase& c) {
    Scene s;
    s.sourceFile = std::string("<") + c.name + ">";
    s.meshes.push_back(makeRectangle());
    Mesh emitter;
    emitter.name = "emitter";
    emitter.positions = c.polygon;
    for (uint32_t i = 1; i + 1 < c.polygon.size(); ++i) emitter.indices.push_back({0, i, i + 1});
    s.meshes.push_back(emitter);
    Material floorMat, black;
    floorMat.reflectance = glm::vec3(kFloorAlbedo);
    black.reflectance = glm::vec3(0.0f);
    s.materials = {floorMat, black};
    Shape floor;
    floor.name = "floor";
    floor.mesh = 0;
    floor.material = 0;
    floor.toWorld = glm::rotate(glm::mat4(1.0f), glm::radians(-90.0f), glm::vec3(1, 0, 0)) *
                    glm::scale(glm::mat4(1.0f), glm::vec3(12.0f));
    Shape light;
    light.name = "emitter";
    light.mesh = 1;
    light.material = 1;
    light.emission = glm::vec3(c.radiance);
    s.shapes = {floor, light};
    s.camera = lookAtCamera(c.cameraOrigin, c.cameraTarget, c.fov);
    return s;
}

// A rectangle at height y, x in [x0, x1], z in [z0, z1], emitting downwards.
std::vector<glm::vec3> ceilingRectangle(float x0, float x1, float z0, float z1, float y) {
    return {{x0, y, z0}, {x1, y, z0}, {x1, y, z1}, {x0, y, z1}};
}

// One case per row (the table is easier to read than clang-format's one field per line).
// clang-format off
const std::vector<PolygonCase>& polygonCases() {
    static const std::vector<PolygonCase> cases = {
        // Facing down at height 0.5: points directly below and far off axis (grazing). Large
        // enough for BSDF sampling to hit it about every other sample.
        {"rectangle overhead", ceilingRectangle(-0.8f, 0.8f, -0.8f, 0.6f, 0.5f), 2.0f,
         {0.0f, 2.2f, 3.2f}, {0.0f, 0.0f, 0.0f}, 65.0f, true},
        // Tilted triangle whose lowest edge is 0.01 above the floor: points very close to it.
        {"triangle close", {{-0.4f, 0.01f, 0.0f}, {0.0f, 0.45f, -0.35f}, {0.4f, 0.01f, 0.0f}},
         3.0f, {0.0f, 0.9f, 1.2f}, {0.0f, 0.0f, 0.1f}, 60.0f, false},
        // Vertical, facing +x: floor points near x = 0 see it almost edge-on (nearly in its
        // plane), points at x < 0 are behind it.
        {"rectangle edge-on",
         {{0.0f, 0.05f, -0.4f}, {0.0f, 0.6f, -0.4f}, {0.0f, 0.6f, 0.4f}, {0.0f, 0.05f, 0.4f}},
         3.0f, {0.6f, 1.4f, 1.3f}, {0.4f, 0.0f, 0.0f}, 60.0f, false},
        // Far and large: 40 x 40 at height 12.
        {"rectangle far", ceilingRectangle(-20.0f, 20.0f, -20.0f, 20.0f, 12.0f), 1.0f,
         {0.0f, 2.0f, 3.0f}, {0.0f, 0.0f, 0.0f}, 50.0f, true},
        // Tiny and far (solid angle ~1e-5 sr: the area-sampling fallback); BSDF sampling
        // would almost never hit it.
        {"rectangle tiny far", ceilingRectangle(-0.05f, 0.05f, -0.05f, 0.05f, 30.0f), 2e5f,
         {0.0f, 2.0f, 3.0f}, {0.0f, 0.0f, 0.0f}, 50.0f, false},
    };
    return cases;
}
// clang-format on

// Per-pixel statistics of an estimator against a known expectation.
struct PixelComparison {
    double maxAbsZ = 0.0, meanZ2 = 0.0;  // over the tested pixels
    double relBias = 0.0, relSe = 0.0;   // of the image mean
    double relExpectedError = 0.0;       // of the expected image mean (its quadrature), summed
    int pixels = 0;                      // with a z-score (nonzero spread)
    double unreached = 0.0;              // |error| of pixels without spread, over the image
};

PixelComparison comparePixels(const std::vector<double>& sum, const std::vector<double>& sum2,
                              int samples, const std::vector<double>& expected,
                              const std::vector<double>& expectedError = {}) {
    PixelComparison c;
    double diff = 0.0, var = 0.0, total = 0.0, unreached = 0.0;
    for (size_t i = 0; i < expected.size(); ++i) {
        if (expected[i] < 0.0) continue;  // not tested
        double mean = sum[i] / samples;
        double v = std::max(sum2[i] / samples - mean * mean, 0.0) * samples / (samples - 1.0);
        diff += mean - expected[i];
        var += v / samples;
        total += expected[i];
        double u = expectedError.empty() ? 0.0 : expectedError[i];
        c.relExpectedError += u;
        double se = std::sqrt(v / samples + u * u);
        if (v > 0.0) {
            double z = (mean - expected[i]) / se;
            c.maxAbsZ = std::max(c.maxAbsZ, std::abs(z));
            c.meanZ2 += z * z;
            ++c.pixels;
        } else {
            // No spread: no sample reached light (or all did equally); no z-score. Their
            // expected light must be negligible, or the estimator is missing it.
            unreached += std::abs(mean - expected[i]);
        }
    }
    c.unreached = total > 0.0 ? unreached / total : 0.0;
    c.meanZ2 /= std::max(c.pixels, 1);
    c.relBias = diff / total;
    c.relSe = std::sqrt(var) / total;
    c.relExpectedError = total > 0.0 ? c.relExpectedError / total : 0.0;
    return c;
}

// Renders frames (one independent estimate each) of r's "pt.color", channel `channel`, until
// the image mean's relative standard error is below `targetRelSe`, checked every `step` frames
// from `minFrames` on, or until `maxFrames`.
struct FrameSchedule {
    int minFrames, step, maxFrames;
    double targetRelSe;
};
struct FrameStudy {
    PixelComparison comparison;
    int frames = 0;
};

FrameStudy renderUntilPrecise(Renderer& r, int channel, const std::vector<double>& expected,
                              const std::vector<double>& expectedError, FrameSchedule schedule) {
    std::vector<double> sum(expected.size(), 0.0), sum2(expected.size(), 0.0);
    FrameStudy study;
    while (true) {
        r.frame();
        ImageData img = r.readOutput("pt.color");
        for (size_t i = 0; i < expected.size(); ++i) {
            double v = img.pixels[i * 4 + channel];
            sum[i] += v;
            sum2[i] += v * v;
        }
        ++study.frames;
        if (study.frames < schedule.minFrames || study.frames % schedule.step != 0) continue;
        study.comparison = comparePixels(sum, sum2, study.frames, expected, expectedError);
        if (study.comparison.relSe < schedule.targetRelSe || study.frames >= schedule.maxFrames)
            return study;
    }
}

// A polygon case's expected pixels (rho / pi * mean of E over the footprint; -1: not tested)
// and their quadrature uncertainty, at kPolygonSize^2 pixels.
constexpr uint32_t kPolygonSize = 32;
struct PolygonExpectation {
    std::vector<double> expected, quadrature;
};
PolygonExpectation polygonExpectation(const PolygonCase& pc, const Scene& scene) {
    constexpr uint32_t kSize = kPolygonSize, kSub = 8;
    static_assert(kSub % 2 == 0);
    // Expected radiance per pixel: rho / pi * mean of E over the footprint.
    std::vector<double> expected(kSize * kSize, 0.0), coarse(kSize * kSize, 0.0);
    {
        json g = {
            {"name", "gbuffer"},
            {"passes", {{{"name", "gbuf"}, {"type", "GBuffer"}, {"params", {{"jitter", false}}}}}},
            {"edges", json::array()},
            {"outputs", {"gbuf.position", "gbuf.vbuffer"}}};
        Renderer r(sharedGpu(), RenderGraph::parse(g.dump(), "<test>"), kSize * kSub, kSize * kSub);
        r.setScene(scene);
        r.frame();
        ImageData pos = r.readOutput("gbuf.position"), vb = r.readOutput("gbuf.vbuffer");
        std::vector<dvec3> poly(pc.polygon.begin(), pc.polygon.end());
        for (uint32_t y = 0; y < kSize * kSub; ++y)
            for (uint32_t x = 0; x < kSize * kSub; ++x) {
                uint32_t i = y * kSize * kSub + x, p = (y / kSub) * kSize + x / kSub;
                if (pos.pixels[i * 4 + 3] == 0.0f || vb.pixels[i * 4 + 3] != 0.0f) {
                    expected[p] = -1e30;  // footprint not entirely on the floor
                    continue;
                }
                dvec3 xw(pos.pixels[i * 4], 0.0, pos.pixels[i * 4 + 2]);
                double L =
                    kFloorAlbedo / M_PI * polygonIrradiance(xw, {0, 1, 0}, poly, pc.radiance);
                expected[p] += L / (kSub * kSub);
                if ((x % 2) && (y % 2)) coarse[p] += L / (kSub * kSub / 4);
            }
    }
    // Skip a one-pixel margin around skipped pixels too: a footprint can cross the floor's
    // edge or the emitter's silhouette between the quadrature points.
    std::vector<double> tested = expected;
    for (int y = 0; y < int(kSize); ++y)
        for (int x = 0; x < int(kSize); ++x)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int u = x + dx, v = y + dy;
                    if (u >= 0 && v >= 0 && u < int(kSize) && v < int(kSize) &&
                        expected[v * kSize + u] < 0.0)
                        tested[y * kSize + x] = -1.0;
                }
    expected = tested;
    // Quadrature uncertainty: the difference to the rule on every other point (which is of
    // lower order, so this overestimates it), added to each pixel's standard error.
    std::vector<double> quadrature(kSize * kSize);
    for (size_t i = 0; i < quadrature.size(); ++i)
        quadrature[i] = std::abs(expected[i] - coarse[i]);
    return {expected, quadrature};
}

// One strategy and sampler on a polygon case, frames until the image mean's standard error is
// below 0.075% (4 SE <= 0.3%).
FrameStudy polygonStudy(const PolygonCase& pc, const Scene& scene, const PolygonExpectation& e,
                        const std::string& strategy, const std::string& sampler) {
    int spp = strategy == "bsdf" ? 64 : 16;
    Renderer r(sharedGpu(),
               ptGraph({{"strategy", strategy},
                        {"sampler", sampler},
                        {"samplesPerPixel", spp},
                        {"maxBounces", 1},
                        {"motionBlur", false}}),
               kPolygonSize, kPolygonSize, 11);
    r.setScene(scene);
    FrameStudy study = renderUntilPrecise(r, 1, e.expected, e.quadrature, {32, 4, 1024, 7.5e-4});
    const PixelComparison& c = study.comparison;
    std::printf(
        "%-20s %-4s %-11s %3d frames x %3d spp, %4d px: rel. bias %+.4f%% (se %.4f%%), "
        "max |z| %.2f, mean z^2 %.3f, unreached %.1e, quadrature %.1e\n",
        pc.name, strategy.c_str(), sampler.c_str(), study.frames, spp, c.pixels, 100 * c.relBias,
        100 * c.relSe, c.maxAbsZ, c.meanZ2, c.unreached, c.relExpectedError);
    return study;
}

}  // namespace

// Direct light from polygonal emitters against Lambert's formula, pixel by pixel, for each
// strategy, and for MIS with the Sobol sampler too. The expectation of a pixel is the
// irradiance averaged over its footprint (4 x 4 midpoint quadrature on pixel-centre GBuffer
// positions at 4x the resolution); pixels whose footprint touches the emitter are skipped. Each
// pixel's estimate is the mean of frames, whose spread gives its standard error: independent
// frames, or for the Sobol sampler consecutive blocks of one sequence per pixel, negatively
// correlated, so that the spread overstates its error (conservative;
// SobolDimensionReuseIsDetected shows that the test still sees a bias through it).
TEST(PathTracer, DirectLightMatchesLambertPolygonFormula) {
    for (const PolygonCase& pc : polygonCases()) {
        Scene scene = polygonScene(pc);
        PolygonExpectation e = polygonExpectation(pc, scene);
        for (auto [strategy, sampler] : {std::pair{"nee", "independent"},
                                         {"mis", "independent"},
                                         {"bsdf", "independent"},
                                         {"mis", "sobol"}}) {
            bool bsdf = std::string(strategy) == "bsdf";
            if (bsdf && !pc.bsdfFeasible) continue;
            const PixelComparison c = polygonStudy(pc, scene, e, strategy, sampler).comparison;
            SCOPED_TRACE(std::string(pc.name) + " " + strategy + " " + sampler);
            EXPECT_GT(c.pixels, 200);
            EXPECT_LT(c.unreached, 1e-4);
            EXPECT_LT(c.relSe, 7.5e-4) << "too noisy to see 0.3%";
            // Floored at 1e-5, the float arithmetic's share: on the tiny far emitter the Sobol
            // sampler's image mean reaches a standard error of 1.6e-6 and sits 2e-6 off.
            EXPECT_LT(std::abs(c.relBias), std::max(4.0 * c.relSe, 1e-5));
            EXPECT_LT(std::abs(c.relBias), 3e-3);
            // Bonferroni over ~1000 pixels (P ~ 6e-4 under the null), and the mean of z^2, which
            // sees a small bias spread over many pixels (~1 +- 0.045 for 1000 pixels).
            EXPECT_LT(c.maxAbsZ, 5.0);
            EXPECT_LT(c.meanZ2, 1.0 + 5.0 * std::sqrt(2.0 / c.pixels));
        }
    }
}

// The Sobol sampler's one way to go wrong: two draws of a sample on the same dimension.
// LOOM_TEST_SOBOL_REUSE_DIMENSION makes every 1D draw repeat the 2D draw before it, so the light
// choice (u.z) equals the first coordinate of the point on the light (u.x): each of the
// rectangle's two triangles is sampled on part of itself only. The comparison above must see it.
TEST(PathTracer, SobolDimensionReuseIsDetected) {
    const PolygonCase& pc = polygonCases()[0];  // rectangle overhead: two triangles
    Scene scene = polygonScene(pc);
    PolygonExpectation e = polygonExpectation(pc, scene);
    ::setenv("LOOM_SHADER_DEFINES", "LOOM_TEST_SOBOL_REUSE_DIMENSION=1", 1);
    const PixelComparison c = polygonStudy(pc, scene, e, "nee", "sobol").comparison;
    ::unsetenv("LOOM_SHADER_DEFINES");
    EXPECT_GT(std::abs(c.relBias), 4.0 * c.relSe);
    EXPECT_GT(c.maxAbsZ, 5.0);
}

// A closed box whose six walls all emit L_e and reflect with albedo rho: every pixel's radiance
// is exactly L_e (1 + rho + ... + rho^n) = L_e (1 - rho^(n+1)) / (1 - rho) at maxBounces n,
// whatever the strategy. NEE samples the walls at every vertex, so a loss of light sampling at
// secondary vertices (or in the corners, where walls meet) shows at n >= 2.
TEST(PathTracer, EmissiveEnclosureMatchesGeometricSeries) {
    constexpr float kLe = 1.0f, kRho = 0.5f;
    constexpr uint32_t kSize = 24;
    Scene s;
    s.sourceFile = "<enclosure>";
    s.meshes.push_back(makeRectangle());
    Material wall;
    wall.reflectance = glm::vec3(kRho);
    s.materials.push_back(wall);
    // Six rectangles facing the centre (makeRectangle faces +z).
    const std::pair<glm::vec3, float> faces[] = {{{0, 1, 0}, 0.0f},  {{0, 1, 0}, 180.0f},
                                                 {{0, 1, 0}, 90.0f}, {{0, 1, 0}, -90.0f},
                                                 {{1, 0, 0}, 90.0f}, {{1, 0, 0}, -90.0f}};
    for (auto [axis, angle] : faces) {
        Shape w;
        w.mesh = 0;
        w.material = 0;
        w.emission = glm::vec3(kLe);
        // Half-size 0.3: every light sample is within ~1 of its shading point, where a shadow
        // ray that only offsets its origin would stop behind the light (the old NEE bug).
        w.toWorld = glm::scale(glm::mat4(1.0f), glm::vec3(0.3f)) *
                    glm::rotate(glm::mat4(1.0f), glm::radians(angle), axis) *
                    glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, -1));
        s.shapes.push_back(w);
    }
    // Off-centre, looking into a corner: walls, edges and the corner itself are in view.
    s.camera = lookAtCamera({0.09f, -0.06f, 0.12f}, {-0.3f, 0.3f, -0.3f}, 100.0f);
    std::vector<double> expected;
    // {maxBounces, rrDepth}: without Russian roulette, and with it from the 5th bounce (the
    // default), where per-frame values are heavy-tailed and only the image mean is tested.
    for (auto [n, rrDepth] : {std::pair{1, 2}, {2, 3}, {3, 4}, {48, 64}, {64, 5}}) {
        bool roulette = rrDepth <= n;
        double L = kLe * (1.0 - std::pow(double(kRho), n + 1)) / (1.0 - kRho);
        expected.assign(kSize * kSize, L);
        for (const char* strategy : {"nee", "mis", "bsdf"}) {
            Renderer r(sharedGpu(),
                       ptGraph({{"strategy", strategy},
                                {"samplesPerPixel", 8},
                                {"maxBounces", n},
                                {"rrDepth", rrDepth},
                                {"motionBlur", false}}),
                       kSize, kSize, 5);
            r.setScene(s);
            // Russian roulette makes the per-frame values heavy-tailed: many frames, so that
            // the standard errors from their spread are reliable.
            FrameStudy study = renderUntilPrecise(r, 0, expected, {}, {128, 8, 512, 5e-4});
            const PixelComparison& c = study.comparison;
            int frames = study.frames;
            std::printf(
                "enclosure n=%-2d rr %-2d %-4s %3d frames: mean %.5f (expected %.5f), rel. bias "
                "%+.4f%% (se %.4f%%), max |z| %.2f, mean z^2 %.3f\n",
                n, rrDepth, strategy, frames, L * (1.0 + c.relBias), L, 100 * c.relBias,
                100 * c.relSe, c.maxAbsZ, c.meanZ2);
            EXPECT_LT(c.relSe, 5e-4) << "n " << n << " " << strategy;
            // BSDF sampling is exact here before Russian roulette (f / p = rho, every ray hits
            // an emitter): no spread at all.
            EXPECT_LE(std::abs(c.relBias), std::max(4.0 * c.relSe, 1e-6))
                << "n " << n << " " << strategy;
            EXPECT_LT(std::abs(c.relBias), 2e-3) << "n " << n << " " << strategy;
            if (!roulette && c.pixels > 0) {
                EXPECT_LT(c.maxAbsZ, 5.0) << "n " << n << " " << strategy;
                EXPECT_LT(c.meanZ2, 1.0 + 5.0 * std::sqrt(2.0 / c.pixels))
                    << "n " << n << " " << strategy;
            }
        }
    }
}

namespace {

// Luminance means of 8 x 8 regions (and of the whole image) over independent frames.
struct StrategyRun {
    RegionStats regions{8}, image{1};
};

constexpr uint32_t kStrategySize = 32;

// Pixels whose footprint sees an emitter directly (4 x 4 pixel-centre GBuffer samples per pixel,
// dilated by one pixel). Their value is the emitter's radiance times its coverage, which every
// strategy samples alike, and that coverage noise would swamp the light-transport comparison.
std::vector<bool> directEmitterMask(const Scene& scene) {
    constexpr uint32_t kSub = 4, n = kStrategySize;
    json g = {
        {"name", "gbuffer"},
        {"passes", {{{"name", "gbuf"}, {"type", "GBuffer"}, {"params", {{"jitter", false}}}}}},
        {"edges", json::array()},
        {"outputs", {"gbuf.vbuffer"}}};
    Renderer r(sharedGpu(), RenderGraph::parse(g.dump(), "<test>"), n * kSub, n * kSub);
    r.setScene(scene);
    ImageData vb = r.readOutput("gbuf.vbuffer");
    std::vector<bool> seen(n * n, false), mask(n * n, false);
    for (uint32_t y = 0; y < n * kSub; ++y)
        for (uint32_t x = 0; x < n * kSub; ++x) {
            const float* v = &vb.pixels[(y * n * kSub + x) * 4];
            if (v[0] == float(~0u)) continue;  // miss
            const Shape& shape = scene.shapes.at(size_t(v[3]));
            if (glm::any(glm::greaterThan(shape.emission, glm::vec3(0.0f))))
                seen[(y / kSub) * n + x / kSub] = true;
        }
    for (int y = 0; y < int(n); ++y)
        for (int x = 0; x < int(n); ++x)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int u = x + dx, w = y + dy;
                    if (u >= 0 && w >= 0 && u < int(n) && w < int(n) && seen[w * n + u])
                        mask[y * n + x] = true;
                }
    return mask;
}

StrategyRun renderStrategy(const Scene& scene, const std::vector<bool>& mask, const char* strategy,
                           int spp, int frames, int maxBounces, uint32_t seed,
                           const char* sampler = "independent") {
    Renderer r(sharedGpu(),
               ptGraph({{"strategy", strategy},
                        {"sampler", sampler},
                        {"samplesPerPixel", spp},
                        {"maxBounces", maxBounces},
                        {"motionBlur", false}}),
               kStrategySize, kStrategySize, seed);
    r.setScene(scene);
    StrategyRun run;
    for (int f = 0; f < frames; ++f) {
        r.frame();
        ImageData img = r.readOutput("pt.color");
        for (uint32_t i = 0; i < img.width * img.height; ++i) {
            float* p = &img.pixels[i * 4];
            float y = mask[i] ? 0.0f : 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
            p[0] = p[1] = p[2] = y;
        }
        run.regions.add(img);
        run.image.add(img);
    }
    return run;
}

// Largest radiance any emitter shows (max channel): with path throughput at most 1 (albedos at
// most 1, importance-sampled weights, no Russian roulette at the test's depth), one BSDF-sampled
// path adds at most this over spp to its pixel.
double maxEmittedRadiance(const Scene& scene) {
    double le = 0.0;
    auto maxc = [](glm::vec3 v) { return double(std::max({v.x, v.y, v.z})); };
    for (const Shape& s : scene.shapes) le = std::max(le, maxc(s.emission));
    for (const Light& l : scene.lights) {
        if (l.type != LightType::Environment && l.type != LightType::Constant) continue;
        double t = 1.0;
        if (l.envTexture >= 0 && size_t(l.envTexture) < scene.textures.size()) {
            const Texture& tex = scene.textures[l.envTexture];
            t = 0.0;
            for (size_t i = 0; i + 3 <= tex.rgba.size(); i += 4)
                t = std::max(
                    {t, double(tex.rgba[i]), double(tex.rgba[i + 1]), double(tex.rgba[i + 2])});
        }
        le = std::max(le, maxc(l.intensity) * l.scale * t);
    }
    return le;
}

// Every strategy reaches some light only through rare emitter hits: BSDF sampling always, and
// NEE and MIS through delta vertices (glass, mirrors, smooth coats, null boundaries), where
// light sampling cannot connect.
// The most one such hit adds to one frame's mean over `pixels` pixels at `spp` samples:
// maxEmittedRadiance / (spp pixels), path throughput being at most 1 there.
double rareHitBound(const Scene& scene, bool bsdfSampling, int spp, double pixels) {
    bool delta = false;
    for (const Shape& s : scene.shapes) {
        if (s.material < 0 || size_t(s.material) >= scene.materials.size()) continue;
        BsdfType t = scene.materials[s.material].type;
        delta = delta || t == BsdfType::Dielectric || t == BsdfType::Conductor ||
                t == BsdfType::Plastic || t == BsdfType::Null;
    }
    return bsdfSampling || delta ? maxEmittedRadiance(scene) / (spp * pixels) : 0.0;
}

// Largest |z| over the regions, and the relative bias the comparison detects at `zLimit` in
// its worst region among those that hold light: at least half their pixels unmasked and a mean
// of at least a quarter of the median region's (dark corners carry no power).
//
// hitA, hitB (rareHitBound): where one side reads low by d and is unbiased, the light it misses
// is rare emitter hits of at most `hit` each, at least d N / hit of them expected over its N
// frames. When none occurred they leave no trace in its spread (an edge-on small light: p ~ 1e-6
// per sample; a caustic behind glass at 64 spp), so their Poisson variance, hit d / N, is added
// to that side's squared standard error. |z| is then at most about the square root of the hits
// the deficit implies: a rare-event test, where the spread alone reads |z| 47 for a deficit of
// 0.6 expected hits (README).
struct Agreement {
    double maxZ = 0.0, detectable = 0.0, medianDetectable = 0.0;
    double maxZSpread = 0.0;        // the same from the spreads alone (no rare-hit term)
    int worstRegion = -1;           // row-major
    double worstA = 0, worstB = 0;  // its two means
};

Agreement compareRegions(const RegionStats& a, const RegionStats& b, double zLimit,
                         const std::vector<double>& unmasked, double hitA = 0.0,
                         double hitB = 0.0) {
    Agreement g;
    std::vector<double> means;
    for (size_t i = 0; i < a.sum.size(); i += 3) means.push_back(b.mean(i));
    std::vector<double> sorted = means;
    std::sort(sorted.begin(), sorted.end());
    double floorMean = 0.25 * sorted[sorted.size() / 2];
    std::vector<double> detect;
    for (size_t i = 0; i < a.sum.size(); i += 3) {
        double se2 = a.stderr2(i) + b.stderr2(i), se = std::sqrt(se2);
        double diff = a.mean(i) - b.mean(i);
        double rare = diff < 0.0 ? hitA * -diff / a.frames : hitB * diff / b.frames;
        double z = se2 + rare > 0.0 ? std::abs(diff) / std::sqrt(se2 + rare) : 0.0;
        if (se > 0.0) g.maxZSpread = std::max(g.maxZSpread, std::abs(diff) / se);
        if (z > g.maxZ) {
            g.maxZ = z;
            g.worstRegion = int(i / 3);
            g.worstA = a.mean(i);
            g.worstB = b.mean(i);
        }
        // Smallest difference d with d = zLimit sqrt(se^2 + hit d / N), in the weaker
        // direction.
        double k = zLimit * zLimit * std::max(hitA / a.frames, hitB / b.frames);
        double d = 0.5 * (k + std::sqrt(k * k + 4.0 * zLimit * zLimit * se2));
        if (unmasked[i / 3] >= 0.5 && b.mean(i) > 0.0 && b.mean(i) >= floorMean)
            detect.push_back(d / b.mean(i));
    }
    std::sort(detect.begin(), detect.end());
    if (!detect.empty()) {
        g.detectable = detect.back();
        g.medianDetectable = detect[detect.size() / 2];
    }
    return g;
}

// Fraction of each region's pixels outside the mask (regions x regions, row-major).
std::vector<double> unmaskedFraction(const std::vector<bool>& mask, int regions) {
    std::vector<double> f(regions * regions, 0.0);
    int n = kStrategySize, per = (n / regions) * (n / regions);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (!mask[y * n + x]) f[(y * regions / n) * regions + x * regions / n] += 1.0 / per;
    return f;
}

}  // namespace

// NEE, MIS and BSDF sampling estimate the same image. The test has power: it sees a 1% bias
// over the image (4 SE) and a 3% bias in any 8 x 8 region that holds light (4.5 SE, Bonferroni
// over the 64 regions), and that power is asserted from the measured standard errors. It also
// fails when a real bias is put into the estimator: the light-sampling pdf scaled by 1.02 in the
// shader (LOOM_TEST_LIGHT_PDF_SCALE through LOOM_SHADER_DEFINES), not numbers scaled afterwards.
// Where a strategy reads low, its standard error includes the Poisson variance of the rare
// emitter hits that deficit implies (compareRegions): BSDF sampling hits a small light seen
// edge-on once in 10^6 samples, NEE reaches a caustic behind glass only by such hits, and a
// region without a hit has no spread to show it.
TEST(PathTracer, StrategiesAgreeOnProjectScenes) {
    struct Case {
        const char* scene;
        int bsdfSpp, neeSpp, bsdfFrames, neeFrames, maxBounces;
    };
    // The budget detects 3% in every lit region of the Cornell box and 0.5% over the image.
    // BSDF sampling carries most of the variance (its regions' standard errors are 3.6x NEE's at
    // equal frames), so it gets twice NEE's frames; the pdf-scaled run below needs only image
    // power and renders a quarter of them. LOOM_PT_STRATEGY_SCALE=k (may be fractional) scales
    // every frame count; LOOM_PT_STRATEGY_SCENES="a.json;b.xml" (paths relative to the source
    // tree) checks other scenes at the same budget.
    double scale = std::getenv("LOOM_PT_STRATEGY_SCALE")
                       ? std::max(0.01, std::atof(std::getenv("LOOM_PT_STRATEGY_SCALE")))
                       : 1.0;
    auto scaled = [&](int frames) { return std::max(2, int(std::lround(frames * scale))); };
    std::vector<Case> cases = {{"scenes/cornell_box.json", 1024, 64, 512, 256, 3}};
    if (const char* e = std::getenv("LOOM_PT_STRATEGY_SCENES")) {
        cases.clear();
        static std::vector<std::string> names;
        std::stringstream ss(e);
        for (std::string n; std::getline(ss, n, ';');)
            if (!n.empty()) names.push_back(n);
        for (auto& n : names) cases.push_back({n.c_str(), 1024, 64, 512, 256, 3});
    }
    for (Case c : cases) {
        std::string path = std::string(LOOM_SOURCE_DIR) + "/" + c.scene;
        if (!std::filesystem::exists(path)) {
            std::printf("%s: not found, skipped\n", path.c_str());
            continue;
        }
        Scene scene;
        try {
            scene = loadScene(path);
        } catch (const std::exception& e) {  // a shared scene without its meshes
            std::printf("%s: cannot load (%s), skipped\n", c.scene, e.what());
            continue;
        }
        scene.camera.path.clear();
        // BSDF sampling cannot reach point, spot or directional lights: no common estimand.
        bool deltaLights =
            std::any_of(scene.lights.begin(), scene.lights.end(), [](const Light& l) {
                return l.type == LightType::Point || l.type == LightType::Spot ||
                       l.type == LightType::Directional;
            });
        if (deltaLights) {
            std::printf("%s: has delta lights, which BSDF sampling cannot reach; skipped\n",
                        c.scene);
            continue;
        }
        std::vector<bool> mask = directEmitterMask(scene);
        // The most one rare emitter hit adds to a frame's 8 x 8-grid region mean and image mean.
        const double perRegion = kStrategySize * kStrategySize / 64.0,
                     perImage = kStrategySize * kStrategySize;
        const double bsdfRegion = rareHitBound(scene, true, c.bsdfSpp, perRegion),
                     bsdfImage = rareHitBound(scene, true, c.bsdfSpp, perImage),
                     neeRegion = rareHitBound(scene, false, c.neeSpp, perRegion),
                     neeImage = rareHitBound(scene, false, c.neeSpp, perImage);
        StrategyRun bsdf =
            renderStrategy(scene, mask, "bsdf", c.bsdfSpp, scaled(c.bsdfFrames), c.maxBounces, 1);
        std::vector<double> unmasked8 = unmaskedFraction(mask, 8),
                            unmasked1 = unmaskedFraction(mask, 1);
        std::map<std::string, StrategyRun> runs;
        for (const char* strategy : {"nee", "mis"}) {
            // Different seeds, so that nee against mis below compares independent estimates.
            StrategyRun& run = runs[strategy] =
                renderStrategy(scene, mask, strategy, c.neeSpp, scaled(c.neeFrames), c.maxBounces,
                               strategy[0] == 'n' ? 2 : 3);
            Agreement regions =
                compareRegions(run.regions, bsdf.regions, 4.5, unmasked8, neeRegion, bsdfRegion);
            Agreement image =
                compareRegions(run.image, bsdf.image, 4.0, unmasked1, neeImage, bsdfImage);
            std::printf(
                "%s %s vs bsdf: image %+.3f%% (|z| %.2f, detects %.2f%%), regions max |z| "
                "%.2f (spread alone %.2f; region %d: %.5g vs %.5g; detects %.2f%%, median "
                "region %.2f%%)\n",
                c.scene, strategy, 100 * (run.image.mean(0) / bsdf.image.mean(0) - 1.0), image.maxZ,
                100 * image.detectable, regions.maxZ, regions.maxZSpread, regions.worstRegion,
                regions.worstA, regions.worstB, 100 * regions.detectable,
                100 * regions.medianDetectable);
            std::fflush(stdout);
            EXPECT_LT(image.maxZ, 4.0) << c.scene << " " << strategy;
            EXPECT_LT(regions.maxZ, 4.5) << c.scene << " " << strategy;
            EXPECT_LT(image.detectable, 0.01) << c.scene << " " << strategy << ": too weak";
            EXPECT_LT(regions.detectable, 0.03) << c.scene << " " << strategy << ": too weak";
        }
        // NEE against MIS: both have low variance where BSDF sampling of a small light is
        // heavy-tailed (a region whose BSDF estimate is a few rare hits nearly always reads
        // low, and its batch spread does not show it), so this separates such regions from a
        // bias at the light-sampling side.
        {
            Agreement regions = compareRegions(runs["nee"].regions, runs["mis"].regions, 4.5,
                                               unmasked8, neeRegion, neeRegion);
            Agreement image = compareRegions(runs["nee"].image, runs["mis"].image, 4.0, unmasked1,
                                             neeImage, neeImage);
            std::printf(
                "%s nee vs mis: image %+.3f%% (|z| %.2f), regions max |z| %.2f (detects "
                "%.2f%%, median region %.2f%%)\n",
                c.scene, 100 * (runs["nee"].image.mean(0) / runs["mis"].image.mean(0) - 1.0),
                image.maxZ, regions.maxZ, 100 * regions.detectable, 100 * regions.medianDetectable);
            EXPECT_LT(image.maxZ, 4.0) << c.scene << " nee vs mis";
            EXPECT_LT(regions.maxZ, 4.5) << c.scene << " nee vs mis";
        }
        // A real bias in light sampling must fail the same comparison.
        ::setenv("LOOM_SHADER_DEFINES", "LOOM_TEST_LIGHT_PDF_SCALE=1.02", 1);
        StrategyRun biased =
            renderStrategy(scene, mask, "nee", c.neeSpp, scaled(c.neeFrames / 4), c.maxBounces, 2);
        ::unsetenv("LOOM_SHADER_DEFINES");
        Agreement image =
            compareRegions(biased.image, bsdf.image, 4.0, unmasked1, neeImage, bsdfImage);
        std::printf("%s nee with light pdf x 1.02 vs bsdf: image %+.3f%% (|z| %.2f)\n", c.scene,
                    100 * (biased.image.mean(0) / bsdf.image.mean(0) - 1.0), image.maxZ);
        EXPECT_GT(image.maxZ, 4.0) << c.scene << ": the comparison does not see a 2% bias";
    }
}

// The Sobol sampler over paths of several bounces (its dimensions run on past the first vertex,
// Russian roulette from the fifth bounce on): MIS with it against MIS with independent numbers
// on the Cornell box, 8 x 8 regions and the image. Its frames are blocks of one sequence per
// pixel, negatively correlated, so their spread overstates its error (conservative); the planted
// dimension reuse (LOOM_TEST_SOBOL_REUSE_DIMENSION) must fail the same comparison.
TEST(PathTracer, SobolSamplerAgreesWithIndependentNumbersOnTheCornellBox) {
    Scene scene = loadScene(std::string(LOOM_SOURCE_DIR) + "/scenes/cornell_box.json");
    scene.camera.path.clear();
    std::vector<bool> mask = directEmitterMask(scene);
    constexpr int kSpp = 64, kBounces = 8;
    const double perRegion = kStrategySize * kStrategySize / 64.0,
                 perImage = kStrategySize * kStrategySize;
    const double rareRegion = rareHitBound(scene, false, kSpp, perRegion),
                 rareImage = rareHitBound(scene, false, kSpp, perImage);
    std::vector<double> unmasked8 = unmaskedFraction(mask, 8),
                        unmasked1 = unmaskedFraction(mask, 1);
    StrategyRun independent = renderStrategy(scene, mask, "mis", kSpp, 256, kBounces, 3);
    for (bool planted : {false, true}) {
        if (planted) ::setenv("LOOM_SHADER_DEFINES", "LOOM_TEST_SOBOL_REUSE_DIMENSION=1", 1);
        StrategyRun sobol =
            renderStrategy(scene, mask, "mis", kSpp, planted ? 16 : 128, kBounces, 4, "sobol");
        ::unsetenv("LOOM_SHADER_DEFINES");
        Agreement regions = compareRegions(sobol.regions, independent.regions, 4.5, unmasked8,
                                           rareRegion, rareRegion);
        Agreement image =
            compareRegions(sobol.image, independent.image, 4.0, unmasked1, rareImage, rareImage);
        std::printf(
            "cornell_box mis sobol%s vs independent: image %+.3f%% (|z| %.2f, detects %.2f%%), "
            "regions max |z| %.2f (detects %.2f%%, median region %.2f%%)\n",
            planted ? " (planted dimension reuse)" : "",
            100 * (sobol.image.mean(0) / independent.image.mean(0) - 1.0), image.maxZ,
            100 * image.detectable, regions.maxZ, 100 * regions.detectable,
            100 * regions.medianDetectable);
        std::fflush(stdout);
        if (planted) {
            EXPECT_GT(image.maxZ, 4.0) << "the comparison does not see the planted reuse";
            continue;
        }
        EXPECT_LT(image.maxZ, 4.0);
        EXPECT_LT(regions.maxZ, 4.5);
        EXPECT_LT(image.detectable, 0.01) << "too weak";
        EXPECT_LT(regions.detectable, 0.03) << "too weak";
    }
}

// Motion blur of a moving camera equals the average of instantaneous frames at sub-shutter
// times (16 midpoint times; the quadrature error is far below the noise here).
TEST(PathTracer, MotionBlurEqualsAverageOfInstants) {
    std::string path = std::string(LOOM_SOURCE_DIR) + "/scenes/cornell_box.json";
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    Scene base = loadScene(path);
    Camera cam = base.camera;
    glm::vec3 o = glm::vec3(cam.toWorld[3]);
    glm::vec3 fwd = glm::normalize(glm::vec3(cam.toWorld[2]));
    glm::vec3 up = glm::normalize(glm::vec3(cam.toWorld[1]));
    glm::vec3 right = glm::normalize(glm::cross(fwd, up));
    float step = 0.08f * glm::length(o);
    cam.path = {{0.0f, o, o + fwd, up, cam.fov},
                {1.0f, o + step * right, o + step * right + fwd, up, cam.fov}};
    cam.fovAxis = Camera::FovAxis::X;

    RegionStats blurred(4), instants(4);
    {
        Scene s = base;
        s.camera = cam;
        s.camera.shutterOpen = 0.0f;
        s.camera.shutterClose = 1.0f;
        Renderer r(sharedGpu(), ptGraph({{"samplesPerPixel", 8}, {"maxBounces", 3}}), 32, 32, 3);
        r.setScene(s);
        for (int f = 0; f < 16; ++f) {
            r.frame();
            blurred.add(r.readOutput("pt.color"));
        }
    }
    {
        Scene s = base;
        s.camera = cam;
        s.camera.shutterOpen = s.camera.shutterClose = 0.0f;
        Renderer r(sharedGpu(), ptGraph({{"samplesPerPixel", 8}, {"maxBounces", 3}}), 32, 32, 5);
        r.setScene(s);
        for (int f = 0; f < 16; ++f) {
            r.setTime((f + 0.5f) / 16.0f);
            r.frame();
            instants.add(r.readOutput("pt.color"));
        }
    }
    double a = 0, b = 0;
    EXPECT_LT(maxZ(blurred, instants, &a, &b), 4.5) << a << " vs " << b;
}

// Motion blur of moving shapes (a box that moves and grows, and the area light, which moves):
// the blurred image equals the average of instantaneous frames at sub-shutter times, through a
// keyframe path and through transform_end. Both shapes move linearly over the shutter, which
// is the motion BVH's model, so the two agree up to noise; the shapes left at shutter open
// (motionBlur off) must fail the same comparison. graphs/pt.json takes the first hit from the
// GBuffer, which must trace it at the path's time (without, |z| 14.9 here).
TEST(PathTracer, MovingShapeMotionBlurEqualsAverageOfInstants) {
    std::string path = std::string(LOOM_SOURCE_DIR) + "/scenes/cornell_box.json";
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    Scene base = loadScene(path);
    auto shapeIndex = [&](const std::string& name) {
        for (size_t i = 0; i < base.shapes.size(); ++i)
            if (base.shapes[i].name == name) return i;
        ADD_FAILURE() << "no shape " << name;
        return size_t(0);
    };
    const size_t box = shapeIndex("tall_box"), light = shapeIndex("light");
    auto withPaths = [&](Scene s) {
        s.shapes[box].path = {{0.0f, glm::vec3(0.0f), glm::quat(1, 0, 0, 0), glm::vec3(1.0f)},
                              {1.0f, glm::vec3(0.45f, 0.0f, 0.25f), glm::quat(1, 0, 0, 0),
                               glm::vec3(1.15f, 1.0f, 1.15f)}};
        s.shapes[light].path = {{0.0f, glm::vec3(0.0f)}, {1.0f, glm::vec3(0.35f, 0.0f, 0.0f)}};
        return s;
    };
    auto withTransformEnd = [&](Scene s) {
        for (size_t i : {box, light}) {
            Scene p = withPaths(base);
            s.shapes[i].moving = true;
            s.shapes[i].toWorldEnd = shapeToWorldAt(p.shapes[i], 1.0f);
        }
        return s;
    };
    const int frames = 24;
    auto render = [&](const Scene& s, bool blur, bool instants, uint32_t seed,
                      bool gbuffer = false) {
        RegionStats stats(4);
        // Through the GBuffer every sample is a first sample: 1 spp, 8x the frames.
        json params = {
            {"samplesPerPixel", gbuffer ? 1 : 8}, {"maxBounces", 3}, {"motionBlur", blur}};
        std::unique_ptr<RenderGraph> graph = ptGraph(params);
        if (gbuffer) {  // graphs/pt.json: the first sample's hit from the GBuffer at its time
            json g = json::parse(test::readFile(std::string(LOOM_SOURCE_DIR) + "/graphs/pt.json"));
            g["passes"][1]["params"] = params;
            g["outputs"] = {"pt.color"};
            graph = RenderGraph::parse(g.dump(), "graphs/pt.json");
        }
        Renderer r(sharedGpu(), std::move(graph), 32, 32, seed);
        r.setScene(s);
        for (int f = 0; f < (gbuffer ? 8 * frames : frames); ++f) {
            if (instants) r.setTime((f + 0.5f) / float(frames));
            r.frame();
            stats.add(r.readOutput("pt.color"));
        }
        return stats;
    };
    Scene instantScene = withPaths(base);
    instantScene.camera.shutterOpen = instantScene.camera.shutterClose = 0.0f;
    RegionStats average = render(instantScene, false, true, 5);

    Scene blurredPath = withPaths(base), blurredEnd = withTransformEnd(base);
    for (Scene* s : {&blurredPath, &blurredEnd}) {
        s->camera.shutterOpen = 0.0f;
        s->camera.shutterClose = 1.0f;
    }
    double a = 0, b = 0;
    double zPath = maxZ(render(blurredPath, true, false, 3), average, &a, &b);
    std::printf("keyframe path: blurred %.5f vs instants %.5f, max |z| %.2f\n", a, b, zPath);
    EXPECT_LT(zPath, 4.5);
    double zGBuffer = maxZ(render(blurredPath, true, false, 11, true), average, &a, &b);
    std::printf(
        "graphs/pt.json (GBuffer first hits): blurred %.5f vs instants %.5f, max |z| %.2f\n", a, b,
        zGBuffer);
    EXPECT_LT(zGBuffer, 4.5);
    double zEnd = maxZ(render(blurredEnd, true, false, 7), average, &a, &b);
    std::printf("transform_end: blurred %.5f vs instants %.5f, max |z| %.2f\n", a, b, zEnd);
    EXPECT_LT(zEnd, 4.5);
    double zOpen = maxZ(render(blurredPath, false, false, 3), average, &a, &b);
    std::printf("shapes at shutter open: %.5f vs instants %.5f, max |z| %.2f\n", a, b, zOpen);
    EXPECT_GT(zOpen, 4.5) << "the comparison cannot see shapes left at shutter open";
}

// The motion-blur code of moving shapes is compiled in only while shapes move over the shutter
// (LOOM_SHAPE_MOTION_BLUR, set by the Renderer): opening the shutter at run time gives the
// blurred image, and closing it again the sharp one, in the same renderer.
TEST(PathTracer, ShutterChangedAtRunTimeRecompilesMotionBlur) {
    Scene s = loadScene(std::string(LOOM_SOURCE_DIR) + "/scenes/cornell_box.json");
    for (Shape& shape : s.shapes)
        if (shape.name == "tall_box")
            shape.path = {{0.0f, glm::vec3(0.0f)}, {1.0f, glm::vec3(0.5f, 0.0f, 0.2f)}};
    s.camera.shutterOpen = 0.0f;
    s.camera.shutterClose = 1.0f;
    Camera closed = s.camera;
    closed.shutterClose = 0.0f;
    json params = {{"samplesPerPixel", 8}, {"maxBounces", 3}};
    auto frames = [](Renderer& r, int n) {
        RegionStats stats(4);
        for (int f = 0; f < n; ++f) {
            r.frame();
            stats.add(r.readOutput("pt.color"));
        }
        return stats;
    };
    // Compiled first without the motion code, then opened: a renderer that did not recompile
    // would keep the box sharp.
    Scene sharpScene = s;
    sharpScene.camera = closed;
    Renderer r(sharedGpu(), ptGraph(params), 32, 32, 3);
    r.setScene(sharpScene);
    RegionStats sharp = frames(r, 24);
    r.scene()->setCamera(s.camera);
    RegionStats blurred = frames(r, 24);
    r.scene()->setCamera(closed);
    RegionStats sharpAgain = frames(r, 24);

    Renderer fresh(sharedGpu(), ptGraph(params), 32, 32, 9);
    fresh.setScene(s);
    RegionStats blurredFresh = frames(fresh, 24);
    EXPECT_LT(maxZ(blurred, blurredFresh), 4.5) << "opening the shutter at run time";
    EXPECT_LT(maxZ(sharpAgain, sharp), 4.5) << "closing it again";
    EXPECT_GT(maxZ(sharp, blurred), 4.5) << "the blur is not visible to the test";
}

// The wavefront schedule (path_tracer_wavefront.comp) runs the megakernel's path_vertex on the
// same random numbers in the same order, so it renders the same image: bit for bit on lavapipe,
// and to the last bits of float elsewhere (a compiler may contract differently per kernel).
// Cases cover what the wavefront keeps between dispatches: V-buffer first hits (graphs/pt.json),
// sample chunks with their own streams (4 spp at 64 bounces = chunks of 3 + 1), each strategy,
// a bounce list that runs empty (wavefrontDepth past every path), only the last dispatch
// (depth 0), misses into an environment, moving shapes at each path's time, AOVs and clamp.
TEST(PathTracer, WavefrontScheduleRendersTheMegakernelsImage) {
    const std::string root = LOOM_SOURCE_DIR;
    Scene cornell = loadScene(root + "/scenes/cornell_box.json");
    Scene glossy = loadScene(root + "/bench/data/peer/glossy_env.json");
    Scene moving = cornell;
    for (Shape& shape : moving.shapes)
        if (shape.name == "tall_box")
            shape.path = {{0.0f, glm::vec3(0.0f)}, {1.0f, glm::vec3(0.5f, 0.0f, 0.2f)}};
    moving.camera.shutterOpen = 0.0f;
    moving.camera.shutterClose = 1.0f;
    struct Case {
        const char* name;
        const Scene* scene;
        json params;
        bool viaGBuffer;
    };
    const std::vector<Case> cases = {
        {"graphs/pt.json, 4 spp in chunks of 3 + 1, 64 bounces",
         &cornell,
         {{"samplesPerPixel", 4}, {"maxBounces", 64}},
         true},
        {"strategy bsdf, depth 2",
         &cornell,
         {{"strategy", "bsdf"}, {"maxBounces", 6}, {"wavefrontDepth", 2}},
         false},
        {"strategy nee, balance heuristic, clamp",
         &cornell,
         {{"strategy", "nee"}, {"misHeuristic", "balance"}, {"clamp", 0.5}},
         false},
        {"depth 0 (all in the last dispatch)", &cornell, {{"wavefrontDepth", 0}}, false},
        {"depth 64 (lists run empty: paths escape)",
         &glossy,
         {{"samplesPerPixel", 2}, {"maxBounces", 64}, {"wavefrontDepth", 64}},
         false},
        {"environment and glossy spheres", &glossy, {{"maxBounces", 16}}, false},
        {"moving shapes, motion blur", &moving, {{"samplesPerPixel", 2}}, true},
        {"sampler sobol, 4 spp in chunks of 3 + 1, 64 bounces",
         &cornell,
         {{"sampler", "sobol"}, {"samplesPerPixel", 4}, {"maxBounces", 64}},
         true},
    };
    const std::vector<std::string> outputs = {"pt.color", "pt.albedo", "pt.direct", "pt.indirect"};
    for (const Case& c : cases) {
        std::vector<std::vector<ImageData>> images;
        for (const char* schedule : {"megakernel", "wavefront"}) {
            json params = c.params;
            params["schedule"] = schedule;
            json g = json::parse(test::readFile(root + "/graphs/pt.json"));
            if (!c.viaGBuffer) {
                g["passes"].erase(0);
                g["edges"] = json::array();
                params["motionBlur"] = true;
            }
            for (auto& p : g["passes"])
                if (p["name"] == "pt") p["params"] = params;
            g["outputs"] = outputs;
            Renderer r(sharedGpu(), RenderGraph::parse(g.dump(), "graphs/pt.json"), 24, 20, 17);
            r.setScene(*c.scene);
            std::vector<ImageData> frames;
            for (int f = 0; f < 2; ++f) {
                r.frame();
                for (const auto& o : outputs) frames.push_back(r.readOutput(o));
            }
            images.push_back(std::move(frames));
        }
        size_t values = 0, identical = 0, outside = 0;
        double sum = 0;
        for (size_t k = 0; k < images[0].size(); ++k) {
            const auto &a = images[0][k].pixels, &b = images[1][k].pixels;
            ASSERT_EQ(a.size(), b.size());
            for (size_t i = 0; i < a.size(); ++i) {
                ++values;
                sum += a[i];
                identical += a[i] == b[i];
                outside += !(std::abs(a[i] - b[i]) <= 1e-5f * std::max(1.0f, std::abs(a[i])));
            }
        }
        std::printf("%s: %zu of %zu values identical, %zu beyond 1e-5 (mean %.5f)\n", c.name,
                    identical, values, outside, sum / double(values));
        EXPECT_EQ(outside, 0u) << c.name;
        EXPECT_GT(sum, 0.0) << c.name << ": a black image proves nothing";
    }
}
