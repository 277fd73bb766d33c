// Reservoirs of caustic paths for spatiotemporal reuse with the manifold shift (Hong et al.
// 2025 Sec. 5): a sample is the light point x_n in light-local coordinates plus the solution
// x̄* it was found with (its first specular vertex, which seeds the shift, and its shape
// sequence, which the shift keeps). Written by PartitionedSMS, read and written by
// ManifoldReSTIRTemporal and ManifoldReSTIRSpatial; host mirror in ManifoldReuse.h.
#ifndef LOOM_MANIFOLD_RESERVOIR_GLSL
#define LOOM_MANIFOLD_RESERVOIR_GLSL

#include "lib/color.glsl"
#include "lib/manifold/sms.glsl"
#include "lib/restir/reservoir.glsl"

const uint MANIFOLD_NO_SHAPE = ~0u;

struct ManifoldSample {
    vec4 x1;       // xyz the first specular vertex (world, in its reservoir's frame), w word 0
                   // of the offset normals' stream (bits; rough casters)
    uvec4 shapes;  // shape of each chain vertex, MANIFOLD_NO_SHAPE after the last
    vec4 light;    // xy light-local coordinates of x_n (a triangle's barycentrics), z light
                   // index (bits), w word 1 of the offset normals' stream (bits)
};

struct ManifoldReservoir {
    PrimaryHit receiver;  // x0's triangle and barycentrics, and the camera point it is seen from
    ManifoldSample s;
    vec4 F;       // rgb f T Le G of s at the receiver (no pdf), w the target luminance(F)
    vec4 weight;  // x the unbiased contribution weight W, y the confidence M, zw unused
};

// Buffer header: which frame layout and shift rules the reservoirs were made under (history
// from other ones is not reused).
struct ManifoldReservoirHeader {
    uvec4 info;  // x magic, y frame width, z frame height, w max chain
};
const uint MANIFOLD_RESERVOIR_MAGIC = 0x4D525356u;

ManifoldReservoir manifold_reservoir_empty(PrimaryHit receiver) {
    ManifoldReservoir r;
    r.receiver = receiver;
    r.s.x1 = vec4(0.0);
    r.s.shapes = uvec4(MANIFOLD_NO_SHAPE);
    r.s.light = vec4(0.0);
    r.F = vec4(0.0);
    r.weight = vec4(0.0, primary_valid(receiver) ? 1.0 : 0.0, 0.0, 0.0);
    return r;
}

// The two words of a sample's offset normals' stream (manifold_offset_stream, sms.glsl).
uvec2 manifold_sample_offset_seed(ManifoldSample s) {
    return uvec2(floatBitsToUint(s.x1.w), floatBitsToUint(s.light.w));
}

void manifold_sample_set_offset_seed(inout ManifoldSample s, uvec2 seed) {
    s.x1.w = uintBitsToFloat(seed.x);
    s.light.w = uintBitsToFloat(seed.y);
}

uint manifold_sample_length(ManifoldSample s) {
    uint k = 0u;
    while (k < 4u && s.shapes[k] != MANIFOLD_NO_SHAPE) ++k;
    return k;
}

// The light end x_n of a sample in the geometry selected now (scene_select_frame): the light
// keeps its local coordinates, so a moving area light carries x_n with it. pdf = 1: reuse
// evaluates f T Le G, and the sample's pdf is in its contribution weight.
ManifoldLight manifold_sample_light_end(ManifoldSample s) {
    uint li = floatBitsToUint(s.light.z);
    ManifoldLight ml = manifold_light_from(vec3(0.0), 1.0, vec3(0.0), li);
    LightGpu l = scene_light(li);
    if (l.type == LIGHT_TRIANGLE) {
        vec3 a, b, c;
        triangle_positions(l.index, a, b, c);
        vec2 uv = s.light.xy;
        ml = manifold_light_from((1.0 - uv.x - uv.y) * a + uv.x * b + uv.y * c, 1.0,
                                 normalize(cross(b - a, c - a)), li);
    } else if (l.type == LIGHT_DIRECTIONAL) {
        ml.y = normalize(l.p0.xyz);
    } else {
        ml.y = l.p0.xyz;
    }
    return ml;
}

// Light-local coordinates of a light point (the inverse of manifold_sample_light_end).
vec4 manifold_light_coords(uint light, vec3 y) {
    LightGpu l = scene_light(light);
    vec2 uv = l.type == LIGHT_TRIANGLE ? triangle_barycentrics(l.index, y) : vec2(0.0);
    return vec4(uv, uintBitsToFloat(light), 0.0);
}

// Streaming resampling (Talbot et al. 2005; Lin et al. 2022 Alg. 1): candidate with resampling
// weight w replaces the kept one with probability w / w_sum.
bool manifold_reservoir_take(inout float w_sum, float w, float u) {
    if (!(w > 0.0)) return false;
    w_sum += w;
    return u * w_sum < w;
}

#endif
