#version 460
// Test kernel (tests/gpu/test_graph_resources_gpu.cpp): adds 1 to every element of a buffer in
// place; the ComputePass binds its input and its in-place output to the same block.
layout(local_size_x = 64) in;
layout(std430) buffer Data { float data[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(data.length())) return;
    data[i] += 1.0;
}
