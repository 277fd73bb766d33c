#pragma once
// GPU mirror of scene::Material: the std430 record declared as `struct Material` in
// shaders/lib/material.glsl. Seven 16-byte slots, no implicit padding, so the C++ layout
// equals the std430 one (array stride 112).
#include <glm/glm.hpp>

#include <cstddef>
#include <cstdint>

#include "core/scene/Scene.h"

namespace loom::scene {

// info.y bits (MATERIAL_FLAG_* in material.glsl).
enum MaterialGpuFlags : uint32_t {
    kMaterialTwoSided = 1u << 0,
    kMaterialBeckmann = 1u << 1,   // else GGX
    kMaterialNonlinear = 1u << 2,  // (rough)plastic 'nonlinear'
    // The normal map's texels hold slopes (normalMapSlopeTexel): bilinear lookups interpolate
    // slopes (the SMS normalmap's use_slopes), and the tangent-space normal is the texel itself.
    kMaterialNormalSlopes = 1u << 3,
};

inline constexpr uint32_t kMaterialNoTexture = 0xffffffffu;

struct MaterialGpu {
    glm::vec4 diffuse{0.5f, 0.5f, 0.5f, 0.0f};     // rgb diffuse reflectance, a alpha
    glm::vec4 specular{1.0f, 1.0f, 1.0f, 1.5f};    // rgb specular reflectance, a eta
    glm::vec4 transmittance{1.0f};                 // rgb specular transmittance, a Fdr_int
    glm::vec4 conductorEta{0.0f};                  // rgb conductor eta, a unused
    glm::vec4 conductorK{1.0f, 1.0f, 1.0f, 0.0f};  // rgb conductor k, a unused
    glm::uvec4 info{0u};                           // type (BsdfType), flags, reserved x2
    // reflectance, specular reflectance, normal map, reserved (kMaterialNoTexture = none)
    glm::uvec4 textures{kMaterialNoTexture};
};

// std430: vec4/uvec4 members have 16-byte alignment and size, so offsets are 0,16,...,96.
static_assert(sizeof(MaterialGpu) == 112, "MaterialGpu must match the GLSL std430 layout");
static_assert(offsetof(MaterialGpu, diffuse) == 0 && offsetof(MaterialGpu, specular) == 16 &&
                  offsetof(MaterialGpu, transmittance) == 32 &&
                  offsetof(MaterialGpu, conductorEta) == 48 &&
                  offsetof(MaterialGpu, conductorK) == 64 && offsetof(MaterialGpu, info) == 80 &&
                  offsetof(MaterialGpu, textures) == 96,
              "MaterialGpu member offsets must match shaders/lib/material.glsl");
// info.x stores BsdfType directly; material.glsl's MATERIAL_* constants follow this order.
static_assert(uint32_t(BsdfType::Diffuse) == 0 && uint32_t(BsdfType::RoughDielectric) == 2 &&
                  uint32_t(BsdfType::RoughConductor) == 4 && uint32_t(BsdfType::Null) == 7,
              "BsdfType order must match MATERIAL_* in shaders/lib/material.glsl");

// Packs a material for the GPU. Clamps alpha to the shader's minimum (1e-4) and precomputes
// the plastic coat's internal diffuse Fresnel reflectance Fdr(1 / eta). A normal map with
// use_slopes sets kMaterialNormalSlopes; the caller points textures.z at the map's slope copy.
MaterialGpu packMaterial(const Material& material);

// A normal map texel (rgb = (n + 1) / 2) as the slope form the SMS normalmap interpolates
// (Zeltner et al. 2020, after LEAN mapping): n normalised, then (n.x / n.z, n.y / n.z, 1), whose
// bilinear interpolation, normalised, is the tangent-space normal. n.z is kept above 1e-3 (a
// texel at or below the horizon has no finite slope).
glm::vec4 normalMapSlopeTexel(glm::vec4 rgba);

// Exact unpolarised dielectric Fresnel reflectance (same convention as fresnel_dielectric in
// shaders/lib/fresnel.glsl: eta = eta_int / eta_ext, negative cosine = arriving from inside).
double fresnelDielectric(double cosThetaI, double eta);

// Hemispherical average 2 * integral_0^1 F(mu, eta) mu dmu of the Fresnel reflectance seen by
// diffuse light arriving from the side with relative IOR eta (Mitsuba
// fresnelDiffuseReflectance). Integrated numerically, with the TIR part in closed form.
double fresnelDiffuseReflectance(double eta);

}  // namespace loom::scene
