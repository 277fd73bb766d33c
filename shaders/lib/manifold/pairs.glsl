// Light-caster pairs of sample-space-partitioned SMS (Hong et al. 2025 Sec. 4.2): pair =
// emitter * casters + caster. Tables built by passes/partitioned_sms/ManifoldPairs.cpp.
#ifndef LOOM_MANIFOLD_PAIRS_GLSL
#define LOOM_MANIFOLD_PAIRS_GLSL

#include "lib/manifold/sms.glsl"
#include "lib/scene.glsl"

// Per emitter object: x first entry, y entries, z area (bits; 0 = point, spot or directional
// light), w the emissive shape (entries: its triangles, local) or ~0u (entries: light indices).
layout(std430) readonly buffer ManifoldEmitterObjects { uvec4 manifold_emitter_objects[]; };
// (index, inclusive area cdf bits).
layout(std430) readonly buffer ManifoldEmitterLights { uvec2 manifold_emitter_lights[]; };
// Per caster: [2c] its world bounding sphere, [2c + 1].x its shape (bits).
layout(std430) readonly buffer ManifoldCasterObjects { vec4 manifold_caster_objects[]; };

uint manifold_caster_count() { return uint(manifold_caster_objects.length()) / 2u; }
uint manifold_pair_count() {
    return uint(manifold_emitter_objects.length()) * manifold_caster_count();
}
uint manifold_pair_emitter(uint pair) { return pair / manifold_caster_count(); }
uint manifold_pair_caster(uint pair) { return pair % manifold_caster_count(); }
vec4 manifold_caster_bound(uint caster) { return manifold_caster_objects[2u * caster]; }
uint manifold_caster_shape(uint caster) {
    return floatBitsToUint(manifold_caster_objects[2u * caster + 1u].x);
}

// A point on the pair's emitter, uniform by area (pdf = pair_pdf / area), or its point or
// directional light (pdf = pair_pdf).
ManifoldLight manifold_sample_pair_light(uint pair, vec3 u, float pair_pdf) {
    uvec4 e = manifold_emitter_objects[manifold_pair_emitter(pair)];
    uint lo = e.x, hi = e.x + e.y - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u.z < uintBitsToFloat(manifold_emitter_lights[mid].y)) hi = mid;
        else lo = mid + 1u;
    }
    uint index = manifold_emitter_lights[lo].x;
    uint light = e.w == ~0u ? index : scene_shape(e.w).light_offset + index;
    ManifoldLight ml = manifold_light_sample_at(light, u.xy);
    float area = uintBitsToFloat(e.z);
    ml.pdf = area > 0.0 ? pair_pdf / area : pair_pdf;
    return ml;
}

#endif
