#version 460
// Test kernel (tests/gpu/test_graph_feedback_gpu.cpp): output -> prev is a previous-frame
// (feedback) self-edge. x counts frames since the history was reset, y = historyReset, z a
// value unique to (pixel, frame), w the z the previous frame wrote (-1 after a reset).
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D prevImage;  // last frame's outputImage
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint historyReset;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    bool reset = pc.historyReset != 0u;
    vec4 prev = reset ? vec4(0.0, 0.0, -1.0, 0.0) : imageLoad(prevImage, p);
    float stamp = float(pc.frameIndex) * 1000.0 + float(p.x) + 100.0 * float(p.y);
    imageStore(outputImage, p, vec4(prev.x + 1.0, reset ? 1.0 : 0.0, stamp, prev.z));
}
