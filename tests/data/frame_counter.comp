#version 460
// Test kernel (passes/common/tests/test_common_passes.cpp): counts frames in a persistent image, restarting
// when the graph reports fresh history (first frame, resize, recompile).
layout(local_size_x = 8, local_size_y = 8) in;
layout(r32f) uniform image2D countImage;  // persistent
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint historyReset;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    float n = pc.historyReset != 0u ? 0.0 : imageLoad(countImage, p).r;
    n += 1.0;
    imageStore(countImage, p, vec4(n));
    imageStore(outputImage, p, vec4(n, float(pc.historyReset), 0.0, 1.0));
}
