// Statistical and analytic tests of the reference path tracer. Tolerances come from the
// measured standard error over independent frames (z-scores), never from a guessed epsilon.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>

#include "core/graph/Renderer.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneGpu.h"
#include "core/scene/SceneLoader.h"
#include "core/scene/Shapes.h"
#include "tests/support/RegionStats.h"

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
        g["passes"].push_back({{"name", "gbuf"}, {"type", "GBuffer"},
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

// A point light over a diffuse plane: L = albedo / pi * I cos(theta) / d^2, exactly (direct
// lighting only, the light is a delta so NEE has no noise). Compared per pixel.
TEST(PathTracer, PointLightOverPlaneMatchesAnalyticIrradiance) {
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
    Light point;
    point.type = LightType::Point;
    point.position = glm::vec3(0.3f, 1.0f, -0.2f);
    point.intensity = glm::vec3(2.0f, 3.0f, 4.0f);
    s.lights.push_back(point);
    s.camera = lookAtCamera({0, 3, 2.5f}, {0, 0, 0}, 45.0f);

    Renderer r(sharedGpu(),
               ptGraph({{"maxBounces", 1}, {"motionBlur", false}, {"samplesPerPixel", 1}}, true),
               32, 32);
    r.setScene(s);
    r.frame();
    ImageData color = r.readOutput("pt.color");
    ImageData pos = r.readOutput("gbuf.position");
    int tested = 0;
    for (uint32_t i = 0; i < color.width * color.height; ++i) {
        if (pos.pixels[i * 4 + 3] == 0.0f) continue;  // miss
        glm::vec3 p(pos.pixels[i * 4], pos.pixels[i * 4 + 1], pos.pixels[i * 4 + 2]);
        glm::vec3 d = point.position - p;
        float dist2 = glm::dot(d, d);
        float cosTheta = std::max(0.0f, glm::normalize(d).y);
        for (int c = 0; c < 3; ++c) {
            double expected = m.reflectance[c] / M_PI * point.intensity[c] * cosTheta / dist2;
            EXPECT_NEAR(color.pixels[i * 4 + c], expected, 1e-4 * expected + 1e-6) << "pixel " << i;
        }
        ++tested;
    }
    EXPECT_GT(tested, 500);
}

// NEE+MIS, BSDF-only and NEE-only estimate the same image: compare 2x2 region means of the
// Cornell box within 4 combined standard errors (12 comparisons per pair; under the null
// hypothesis |z| > 4 has probability ~8e-4 per pair).
TEST(PathTracer, StrategiesAgreeOnCornellBox) {
    std::string path = std::string(LOOM_SOURCE_DIR) + "/scenes/cornell_box.json";
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    std::vector<RegionStats> stats;
    for (const char* strategy : {"mis", "bsdf", "nee"}) {
        Renderer r(sharedGpu(),
                   ptGraph({{"strategy", strategy}, {"samplesPerPixel", 8}, {"maxBounces", 4}}),
                   32, 32, 17);
        r.loadScene(path);
        RegionStats rs(2);
        for (int f = 0; f < 24; ++f) {
            r.frame();
            rs.add(r.readOutput("pt.color"));
        }
        stats.push_back(rs);
    }
    double a = 0, b = 0;
    EXPECT_LT(maxZ(stats[0], stats[1], &a, &b), 4.0) << "mis vs bsdf: " << a << " vs " << b;
    EXPECT_LT(maxZ(stats[0], stats[2], &a, &b), 4.0) << "mis vs nee: " << a << " vs " << b;
    // The test must be able to fail: a 5% brighter image is detected.
    RegionStats scaled = stats[1];
    for (auto& x : scaled.sum) x *= 1.05;
    for (auto& x : scaled.sum2) x *= 1.05 * 1.05;
    EXPECT_GT(maxZ(stats[0], scaled), 4.0) << "the comparison is too weak to see a 5% bias";
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
    cam.path = {{0.0f, o, o + fwd, up, cam.fov}, {1.0f, o + step * right, o + step * right + fwd, up, cam.fov}};
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
