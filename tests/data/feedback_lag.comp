#version 460
// Test kernel (tests/gpu/test_graph_feedback_gpu.cpp): reads a buffer this frame (cur) and its
// previous-frame copy (prev); writes (cur, prev or -1 after a reset, historyReset, 1).
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer Cur { float cur[]; };
layout(std430) readonly buffer Prev { float prev[]; };
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint historyReset;
} pc;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, pc.frameSize))) return;
    uint i = p.y * pc.frameSize.x + p.x;
    float last = pc.historyReset != 0u ? -1.0 : prev[i];
    imageStore(outputImage, ivec2(p), vec4(cur[i], last, float(pc.historyReset), 1.0));
}
