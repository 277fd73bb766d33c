#version 460
// Test kernel (tests/gpu/test_bsdf.cpp): microfacet.glsl terms for (wo, m) pairs.
#include "lib/microfacet.glsl"

layout(local_size_x = 64) in;
layout(std430) readonly buffer WoBuffer { vec4 wos[]; };
layout(std430) readonly buffer NormalBuffer { vec4 normals[]; };
layout(std430) writeonly buffer ResultBuffer { vec4 results[]; };  // D, G1(wo), pdf, 0
layout(push_constant) uniform Params {
    uint count;
    uint woCount;
    uint dist;
    float alpha;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec3 wo = wos[pc.woCount == 1u ? 0u : i].xyz;
    vec3 m = normals[i].xyz;
    results[i] = vec4(microfacet_d(pc.dist, pc.alpha, m), microfacet_g1(pc.dist, pc.alpha, wo, m),
                      microfacet_sample_pdf(pc.dist, pc.alpha, wo, m), 0.0);
}
