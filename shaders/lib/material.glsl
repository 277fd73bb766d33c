// GPU material record, mirrored by core/scene/MaterialGpu.h (std430, 112 bytes, seven 16-byte
// slots; packMaterial fills it). Textures are resolved by the caller: it overwrites
// diffuse.rgb (reflectance texture) and specular.rgb (specular texture) with the texels before
// calling the BSDF.
#ifndef LOOM_MATERIAL_GLSL
#define LOOM_MATERIAL_GLSL

// Same order as loom::scene::BsdfType.
const uint MATERIAL_DIFFUSE = 0u;
const uint MATERIAL_DIELECTRIC = 1u;
const uint MATERIAL_ROUGH_DIELECTRIC = 2u;
const uint MATERIAL_CONDUCTOR = 3u;
const uint MATERIAL_ROUGH_CONDUCTOR = 4u;
const uint MATERIAL_PLASTIC = 5u;
const uint MATERIAL_ROUGH_PLASTIC = 6u;
const uint MATERIAL_NULL = 7u;

// info.y bits.
const uint MATERIAL_FLAG_TWO_SIDED = 1u;
const uint MATERIAL_FLAG_BECKMANN = 2u;   // else GGX
const uint MATERIAL_FLAG_NONLINEAR = 4u;  // (rough)plastic 'nonlinear' (Mitsuba)
const uint MATERIAL_FLAG_NORMAL_SLOPES = 8u;  // the normal map's texels hold slopes (use_slopes)

const uint MATERIAL_NO_TEXTURE = 0xffffffffu;

struct Material {
    vec4 diffuse;        // rgb diffuse reflectance, a microfacet alpha
    vec4 specular;       // rgb specular reflectance, a eta = int_ior / ext_ior
    vec4 transmittance;  // rgb specular transmittance, a plastic Fdr_int (see packMaterial)
    vec4 cond_eta;       // rgb conductor eta (relative to the exterior), a unused
    vec4 cond_k;         // rgb conductor k, a unused
    uvec4 info;          // x type, y flags, zw reserved
    uvec4 textures;      // x reflectance, y specular reflectance, z normal map, w reserved
};

// The material types the scene has (bit t: MATERIAL t), a compile-time constant the Renderer
// defines from its scene (SceneGpu::materialTypes; all types without one). llvmpipe (Mesa 22)
// runs the straight-line code of every if-block whether a lane takes it or not (only loops end
// early), so the code of a type the scene lacks must not be in a kernel at all: dispatch on
// material types with material_is, whose answer is a constant false for those types.
#ifndef LOOM_SCENE_MATERIALS
#define LOOM_SCENE_MATERIALS 0xffu
#endif
bool material_type_present(uint t) { return ((uint(LOOM_SCENE_MATERIALS) >> t) & 1u) != 0u; }

// A scene with one material type makes the type itself a constant.
uint material_type(Material m) {
    const uint types = uint(LOOM_SCENE_MATERIALS);
    return bitCount(types) == 1 ? uint(findLSB(types)) : m.info.x;
}
bool material_is(uint type, uint t) { return material_type_present(t) && type == t; }
bool material_two_sided(Material m) { return (m.info.y & MATERIAL_FLAG_TWO_SIDED) != 0u; }
bool material_nonlinear(Material m) { return (m.info.y & MATERIAL_FLAG_NONLINEAR) != 0u; }
bool material_normal_slopes(Material m) { return (m.info.y & MATERIAL_FLAG_NORMAL_SLOPES) != 0u; }
// MICROFACET_GGX (0) or MICROFACET_BECKMANN (1), see microfacet.glsl.
uint material_distribution(Material m) {
    return (m.info.y & MATERIAL_FLAG_BECKMANN) != 0u ? 1u : 0u;
}
float material_alpha(Material m) { return m.diffuse.a; }
float material_eta(Material m) { return m.specular.a; }
// Hemispherical average of the internal Fresnel reflectance of the coat, Fdr(1 / eta).
float material_fdr_int(Material m) { return m.transmittance.a; }
// The texture slots some material of the scene uses, a compile-time constant the Renderer
// defines (SceneGpu::textureUses; all without a scene), so that texture lookups a scene never
// makes are compiled out: bit 0 reflectance, 1 specular reflectance, 2 normal map.
#ifndef LOOM_SCENE_TEXTURES
#define LOOM_SCENE_TEXTURES 0x7u
#endif
// Texture indices, MATERIAL_NO_TEXTURE when constant.
uint material_reflectance_texture(Material m) {
    return (uint(LOOM_SCENE_TEXTURES) & 1u) != 0u ? m.textures.x : MATERIAL_NO_TEXTURE;
}
uint material_specular_texture(Material m) {
    return (uint(LOOM_SCENE_TEXTURES) & 2u) != 0u ? m.textures.y : MATERIAL_NO_TEXTURE;
}
uint material_normal_map(Material m) {
    return (uint(LOOM_SCENE_TEXTURES) & 4u) != 0u ? m.textures.z : MATERIAL_NO_TEXTURE;
}

#endif
