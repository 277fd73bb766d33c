#version 460
// Test kernel (tests/gpu/test_envmap.cpp): envmap_pdf and envmap_eval for world directions.
#include "lib/envmap.glsl"

layout(local_size_x = 64) in;
layout(std430) readonly buffer DirBuffer { vec4 dirs[]; };
layout(std430) writeonly buffer ResultBuffer { vec4 results[]; };  // pdf, radiance
layout(push_constant) uniform Params {
    uint count;
    uint index;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec3 d = dirs[i].xyz;
    results[i] = vec4(envmap_pdf(pc.index, d), envmap_eval(pc.index, d));
}
