#version 460
// Test kernel (tests/gpu/test_sampler.cpp): the padded Sobol sampler's first draws of one
// sample. Input row 0 per column: (pixel.x, pixel.y, sample index, seed). Output rows:
// 0 (2D draw, 1D draw, 1D draw), 1 (2D draw, 2D draw): dimensions 0..5 of the sample.
#define RNG_SOBOL 1
#include "lib/rng.glsl"

layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= int(pc.frameSize.x)) return;
    vec4 in0 = imageLoad(inputImage, ivec2(x, 0));
    Rng rng = rng_sample_init(uvec2(in0.xy), uint(in0.z), uint(in0.w));
    vec2 a = rng_next2(rng);
    float b = rng_next(rng), c = rng_next(rng);
    vec2 d = rng_next2(rng), e = rng_next2(rng);
    imageStore(outputImage, ivec2(x, 0), vec4(a, b, c));
    imageStore(outputImage, ivec2(x, 1), vec4(d, e));
}
