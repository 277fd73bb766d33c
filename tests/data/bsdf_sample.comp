#version 460
// Test kernel (tests/gpu/test_bsdf.cpp): draws `count` BSDF samples for one material and one
// wo, and evaluates bsdf_eval / bsdf_pdf at each sampled direction for the consistency check.
#include "lib/rng.glsl"
#include "lib/bsdf.glsl"

layout(local_size_x = 64) in;
layout(std430) readonly buffer MaterialBuffer { Material materials[]; };
layout(std430) writeonly buffer SampleBuffer { vec4 samples[]; };  // wi, pdf
layout(std430) writeonly buffer ValueBuffer { vec4 values[]; };    // f, flags (bits)
layout(std430) writeonly buffer CheckBuffer { vec4 checks[]; };    // bsdf_eval(wi), bsdf_pdf(wi)
layout(std430) writeonly buffer EtaBuffer { float etas[]; };
layout(push_constant) uniform Params {
    vec3 wo;
    uint count;
    uint seed;
    uint mode;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Material m = materials[0];
    Rng rng = rng_init(uvec2(i, 0u), 0u, pc.seed);
    vec3 u = vec3(rng_next(rng), rng_next2(rng));
    BsdfSample s = bsdf_sample(m, pc.wo, u, pc.mode);
    samples[i] = vec4(s.wi, s.pdf);
    values[i] = vec4(s.f, uintBitsToFloat(s.flags));
    checks[i] = vec4(bsdf_eval(m, pc.wo, s.wi, pc.mode), bsdf_pdf(m, pc.wo, s.wi));
    etas[i] = s.eta;
}
