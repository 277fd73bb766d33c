#version 460
// Test kernel (tests/gpu/test_bsdf.cpp): bsdf_eval and bsdf_pdf for a list of (wo, wi) pairs;
// with woCount == 1 every wi shares wos[0] (pdf quadrature grids).
#include "lib/bsdf.glsl"

layout(local_size_x = 64) in;
layout(std430) readonly buffer MaterialBuffer { Material materials[]; };
layout(std430) readonly buffer WoBuffer { vec4 wos[]; };
layout(std430) readonly buffer WiBuffer { vec4 wis[]; };
layout(std430) writeonly buffer ResultBuffer { vec4 results[]; };  // eval, pdf
layout(push_constant) uniform Params {
    uint count;
    uint woCount;
    uint mode;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Material m = materials[0];
    vec3 wo = wos[pc.woCount == 1u ? 0u : i].xyz;
    vec3 wi = wis[i].xyz;
    results[i] = vec4(bsdf_eval(m, wo, wi, pc.mode), bsdf_pdf(m, wo, wi));
}
