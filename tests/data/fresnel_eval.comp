#version 460
// Test kernel (tests/gpu/test_bsdf.cpp): fresnel.glsl against a CPU reference.
// params[i] = (cos_theta_i, eta, conductor eta, conductor k), one value for every channel.
#include "lib/fresnel.glsl"

layout(local_size_x = 64) in;
layout(std430) readonly buffer ParamBuffer { vec4 params[]; };
layout(std430) writeonly buffer ResultBuffer { vec4 results[]; };  // F, cos_t, F_conductor, 0
layout(push_constant) uniform Params {
    uint count;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec4 p = params[i];
    float cos_t;
    float F = fresnel_dielectric(p.x, p.y, cos_t);
    vec3 Fc = fresnel_conductor(p.x, vec3(p.z), vec3(p.w));
    results[i] = vec4(F, cos_t, Fc.g, 0.0);
}
