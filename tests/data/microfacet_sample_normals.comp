#version 460
// Test kernel (tests/gpu/test_bsdf.cpp): microfacet_sample_normals at independent random numbers
// (one pair per invocation), with D(m) of each normal.
#include "lib/microfacet.glsl"
#include "lib/rng.glsl"

layout(local_size_x = 64) in;
layout(std430) writeonly buffer ResultBuffer { vec4 results[]; };  // m, D(m)
layout(push_constant) uniform Params {
    uint count;
    uint dist;
    float alpha;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Rng rng = rng_init(uvec2(i, 0u), 0u, 7u);
    vec2 u = rng_next2(rng);
    vec3 m = microfacet_sample_normals(pc.dist, pc.alpha, u);
    results[i] = vec4(m, microfacet_d(pc.dist, pc.alpha, m));
}
