#pragma once
// Caustic scenes with closed forms, shared by the caustic estimators' tests (SMS, MNEE with
// dimension reduction): a flat mirror (image source) and the flat pool.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <glm/glm.hpp>
#include <string>
#include <utility>

#include "core/graph/Renderer.h"
#include "core/util/JsonSource.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/KernelColumns.h"
#include "tests/support/RegionStats.h"

namespace loom::test {

// A mirror (perfect conductor, facing down) at y = 2 over a diffuse floor, point light below it.
inline const char* kMirrorScene = R"({
  "loom_scene": 1,
  "camera": {"origin": [0, 1.5, 3], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
  "materials": {"mirror": {"type": "conductor", "metal": "none"},
                "floor": {"type": "diffuse", "reflectance": 0.5}},
  "shapes": [
    {"name": "floor", "type": "rectangle", "material": "floor", "caustic_receiver": true,
     "transform": [{"scale": 4}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}]},
    {"name": "mirror", "type": "rectangle", "material": "mirror", "caustic_caster": true,
     "transform": [{"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 2, 0]}]}],
  "lights": [{"type": "point", "position": [0.3, 1, 0], "intensity": 1, "caustic_emitter": true}]
})";

// Unpolarised dielectric Fresnel reflectance from the rarer side, cos_i > 0, eta = n_t / n_i.
inline double fresnelDielectric(double cosI, double eta) {
    double sin2T = (1 - cosI * cosI) / (eta * eta);
    if (sin2T >= 1) return 1;
    double cosT = std::sqrt(1 - sin2T);
    double rs = (cosI - eta * cosT) / (cosI + eta * cosT),
           rp = (eta * cosI - cosT) / (eta * cosI + cosT);
    return 0.5 * (rs * rs + rp * rp);
}

// A pool: floor (albedo 0.5) at y = 0 under a flat water surface (IOR 1.33) at y = 1, seen by
// a camera under water; a light above. The caustic on the floor in closed form:
//  - directional light of irradiance E from polar angle theta: the beam stays parallel, so
//    E_floor = E cos(theta) (1 - F(theta)), the same everywhere;
//  - point light of intensity I at height 1 above the surface: rho(theta_a) = tan theta_a +
//    tan theta_w (sin theta_a = 1.33 sin theta_w) maps the emission angle to the floor radius,
//    so E_floor = I (1 - F) sin theta_a / (rho d rho / d theta_a).
// Flux crosses the surface without the radiance's 1/eta^2: a radiance throughput here reads
// 1.33^2 = 1.77 times too bright.
inline std::string poolScene(const std::string& light) {
    return R"({
      "loom_scene": 1,
      "camera": {"origin": [0, 0.6, 1.0], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
      "materials": {"water": {"type": "dielectric", "ior": 1.33},
                    "floor": {"type": "diffuse", "reflectance": 0.5}},
      "shapes": [
        {"name": "floor", "type": "rectangle", "material": "floor", "caustic_receiver": true,
         "transform": [{"scale": 4}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}]},
        {"name": "water", "type": "rectangle", "material": "water", "caustic_caster": true,
         "transform": [{"scale": 4}, {"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"translate": [0, 1, 0]}]}],
      "lights": [)" +
           light + R"(]
    })";
}

inline double poolPointCaustic(glm::dvec3 x, glm::dvec3 light) {
    double D = std::hypot(x.x - light.x, x.z - light.z);
    auto rho = [](double ta) { return std::tan(ta) + std::tan(std::asin(std::sin(ta) / 1.33)); };
    double lo = 0, hi = 1.5;
    for (int i = 0; i < 200; ++i) {
        double m = 0.5 * (lo + hi);
        (rho(m) > D ? hi : lo) = m;
    }
    double ta = 0.5 * (lo + hi), h = 1e-6;
    double drho = (rho(ta + h) - rho(ta - h)) / (2 * h);
    double E = (1 - fresnelDielectric(std::cos(ta), 1.33)) * std::sin(ta) / (D * drho);
    return 0.5 / M_PI * E;
}

// The caustic means of `pass` (named "sms" or any name; its port `caustic`) over the image of
// the scene `sceneText` (16 x 16) against the closed form at the GBuffer's pixel centres on the
// floor (y = 0).
inline std::pair<RegionStats, double> floorCaustic(
    const json& pass, const std::string& sceneText,
    const std::function<double(glm::dvec3)>& closedForm, int frames) {
    TempDir dir("loom-sms-floor");
    auto scene = sceneFromJson(sceneText, dir);
    json g = {{"passes",
               {pass, {{"name", "gbuf"}, {"type", "GBuffer"}, {"params", {{"jitter", false}}}}}},
              {"edges", json::array()},
              {"outputs", {pass["name"].get<std::string>() + ".caustic", "gbuf.position"}}};
    constexpr uint32_t kSize = 16;
    Renderer r(gpuContext(), RenderGraph::parse(g.dump(), "<test>"), kSize, kSize, 1);
    r.setScene(scene);
    RegionStats stats(1);
    double analytic = 0;
    for (int f = 0; f < frames; ++f) {
        r.frame();
        if (f == 0) {
            ImageData pos = r.readOutput("gbuf.position");
            for (uint32_t y = 0; y < kSize; ++y)
                for (uint32_t x = 0; x < kSize; ++x) {
                    glm::dvec3 p(pos.at(x, y, 0), pos.at(x, y, 1), pos.at(x, y, 2));
                    // The floor only (the camera sees nothing else; kept as a guard).
                    if (pos.at(x, y, 3) > 0 && std::abs(p.y) < 1e-3)
                        analytic += closedForm(p) / double(kSize * kSize);
                }
        }
        stats.add(r.readOutput(pass["name"].get<std::string>() + ".caustic"));
    }
    return {stats, analytic};
}

// The same on the flat pool under `light`.
inline std::pair<RegionStats, double> poolCaustic(
    const json& pass, const std::string& light, const std::function<double(glm::dvec3)>& closedForm,
    int frames) {
    return floorCaustic(pass, poolScene(light), closedForm, frames);
}

// The caustic of `pass` on the flat pool against the closed forms, within 3 standard errors
// plus the stated allowance: a directional light (irradiance 2 from (0.3, 1, 0.2), constant
// E cos(theta) (1 - F) on the floor) and a point light (poolPointCaustic). `what` names the
// estimator in the messages.
inline void expectPoolDirectionalClosedForm(const json& pass, int frames, const char* what) {
    // Direction towards the light (0.3, 1, 0.2) normalised: cos theta = 1 / |(0.3, 1, 0.2)|.
    double len = std::sqrt(0.09 + 1 + 0.04), cosT = 1 / len;
    double expect = 0.5 / M_PI * 2.0 * cosT * (1 - fresnelDielectric(cosT, 1.33));
    auto [stats, analytic] = poolCaustic(
        pass,
        R"({"type": "directional", "direction": [-0.3, -1, -0.2], "irradiance": 2, "caustic_emitter": true})",
        [&](glm::dvec3) { return expect; }, frames);
    double se = std::sqrt(stats.stderr2(0));
    EXPECT_LT(std::abs(stats.mean(0) - analytic), 3 * se + 1e-3 * analytic)
        << what << " " << stats.mean(0) << " +- " << se << " closed form " << analytic;
    std::printf("pool, directional (%s): %.6f +- %.6f vs %.6f\n", what, stats.mean(0), se,
                analytic);
}

inline void expectPoolPointClosedForm(const json& pass, int frames, const char* what) {
    glm::dvec3 light(0.2, 2, -0.3);
    auto [stats, analytic] = poolCaustic(
        pass,
        R"({"type": "point", "position": [0.2, 2, -0.3], "intensity": 1, "caustic_emitter": true})",
        [&](glm::dvec3 x) { return poolPointCaustic(x, light); }, frames);
    double se = std::sqrt(stats.stderr2(0));
    // Pixel-centre closed form vs the jittered estimate: the caustic is smooth (second-order
    // difference, well below 0.5% here).
    EXPECT_LT(std::abs(stats.mean(0) - analytic), 3 * se + 5e-3 * analytic)
        << what << " " << stats.mean(0) << " +- " << se << " closed form " << analytic;
    std::printf("pool, point light (%s): %.6f +- %.6f vs %.6f\n", what, stats.mean(0), se,
                analytic);
}

}  // namespace loom::test
