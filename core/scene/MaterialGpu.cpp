#include "core/scene/MaterialGpu.h"

#include <algorithm>
#include <cmath>

namespace loom::scene {

double fresnelDielectric(double cosThetaI, double eta) {
    cosThetaI = std::clamp(cosThetaI, -1.0, 1.0);
    // Arriving from inside: the IOR ratio across the interface inverts.
    if (cosThetaI < 0.0) {
        eta = 1.0 / eta;
        cosThetaI = -cosThetaI;
    }
    const double sin2T = (1.0 - cosThetaI * cosThetaI) / (eta * eta);
    if (sin2T >= 1.0) return 1.0;  // total internal reflection
    const double cosThetaT = std::sqrt(1.0 - sin2T);
    const double rs = (cosThetaI - eta * cosThetaT) / (cosThetaI + eta * cosThetaT);
    const double rp = (eta * cosThetaI - cosThetaT) / (eta * cosThetaI + cosThetaT);
    return 0.5 * (rs * rs + rp * rp);
}

double fresnelDiffuseReflectance(double eta) {
    // Below the critical cosine mu_c (eta < 1) F = 1: that part integrates to mu_c^2.
    const double muC = eta < 1.0 ? std::sqrt(1.0 - eta * eta) : 0.0;
    // Composite Simpson on [mu_c, 1] after mu = mu_c + (1 - mu_c) t^2, which removes the
    // sqrt(mu - mu_c) behaviour of F at the critical angle.
    constexpr int kIntervals = 4096;
    const double h = 1.0 / kIntervals;
    double sum = 0.0;
    for (int i = 0; i <= kIntervals; ++i) {
        const double t = i * h;
        const double mu = muC + (1.0 - muC) * t * t;
        const double w = (i == 0 || i == kIntervals) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += w * fresnelDielectric(mu, eta) * mu * 2.0 * (1.0 - muC) * t;
    }
    return muC * muC + 2.0 * sum * h / 3.0;
}

MaterialGpu packMaterial(const Material& material) {
    MaterialGpu g;
    const float alpha = std::max(material.alpha, 1e-4f);
    g.diffuse = glm::vec4(material.reflectance, alpha);
    g.specular = glm::vec4(material.specularReflectance, material.eta);
    float fdrInt = 0.0f;
    if (material.type == BsdfType::Plastic || material.type == BsdfType::RoughPlastic)
        fdrInt = float(fresnelDiffuseReflectance(1.0 / material.eta));
    g.transmittance = glm::vec4(material.specularTransmittance, fdrInt);
    g.conductorEta = glm::vec4(material.conductorEta, 0.0f);
    g.conductorK = glm::vec4(material.conductorK, 0.0f);
    uint32_t flags = 0;
    if (material.twoSided) flags |= kMaterialTwoSided;
    if (material.distribution == Microfacet::Beckmann) flags |= kMaterialBeckmann;
    if (material.nonlinear) flags |= kMaterialNonlinear;
    if (material.normalMap >= 0 && material.normalMapUseSlopes) flags |= kMaterialNormalSlopes;
    const auto texture = [](int index) {
        return index < 0 ? kMaterialNoTexture : static_cast<uint32_t>(index);
    };
    g.info = glm::uvec4(static_cast<uint32_t>(material.type), flags, 0u, 0u);
    g.textures = glm::uvec4(texture(material.reflectanceTexture),
                            texture(material.specularReflectanceTexture),
                            texture(material.normalMap), kMaterialNoTexture);
    return g;
}

glm::vec4 normalMapSlopeTexel(glm::vec4 rgba) {
    glm::vec3 n = 2.0f * glm::vec3(rgba) - 1.0f;
    float len = glm::length(n);
    n = len > 0.0f ? n / len : glm::vec3(0.0f, 0.0f, 1.0f);
    float z = std::max(n.z, 1e-3f);
    return glm::vec4(n.x / z, n.y / z, 1.0f, rgba.a);
}

}  // namespace loom::scene
