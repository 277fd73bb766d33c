#version 460
// Test kernel (passes/common/tests/test_common_passes.cpp): (2r+1)^2 box blur with clamp-to-edge addressing.
// Samples are summed row by row, left to right, so the CPU reference adds in the same order.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    int radius;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    ivec2 last = imageSize(inputImage) - 1;
    vec4 sum = vec4(0.0);
    for (int dy = -pc.radius; dy <= pc.radius; ++dy)
        for (int dx = -pc.radius; dx <= pc.radius; ++dx)
            sum += imageLoad(inputImage, clamp(p + ivec2(dx, dy), ivec2(0), last));
    float n = float((2 * pc.radius + 1) * (2 * pc.radius + 1));
    imageStore(outputImage, p, sum / n);
}
