#version 460
// Test kernel (tests/gpu/test_graph_feedback_gpu.cpp): a buffer value unique to (element, frame).
layout(local_size_x = 64) in;
layout(std430) writeonly buffer Values { float values[]; };
layout(push_constant) uniform Params {
    uint frameIndex;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(values.length())) return;
    values[i] = float(pc.frameIndex) * 1000.0 + float(i);
}
