#version 460
// Test kernel (tests/gpu/test_envmap.cpp): envmap_sample draws, with envmap_pdf and
// envmap_eval re-evaluated at each sampled direction.
#include "lib/rng.glsl"
#include "lib/envmap.glsl"

layout(local_size_x = 64) in;
layout(std430) writeonly buffer SampleBuffer { vec4 samples[]; };  // world direction, pdf
layout(std430) writeonly buffer CheckBuffer { vec4 checks[]; };    // envmap_pdf, envmap_eval
layout(push_constant) uniform Params {
    uint count;
    uint seed;
    uint index;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Rng rng = rng_init(uvec2(i, 0u), 0u, pc.seed);
    float pdf;
    vec3 d = envmap_sample(pc.index, rng_next2(rng), pdf);
    samples[i] = vec4(d, pdf);
    checks[i] = vec4(envmap_pdf(pc.index, d), envmap_eval(pc.index, d));
}
