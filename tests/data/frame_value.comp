#version 460
// Test kernel (passes/common/tests/test_common_passes.cpp): a value that depends on pixel and frame index,
// plus a constant offset, so Accumulate's mean and variance can be checked on the CPU.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    float offset;
} pc;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, pc.frameSize))) return;
    uint f = pc.frameIndex;
    vec4 v = vec4(float((f * 7u + p.x * 3u + p.y * 5u) % 11u), float(f % 4u) * 0.5,
                  float((f * f + p.x) % 13u) * 0.25, 1.0);
    imageStore(outputImage, ivec2(p), v + pc.offset);
}
