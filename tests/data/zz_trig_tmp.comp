#version 460
layout(local_size_x = 64) in;
layout(std430) readonly buffer InBuffer { float xs[]; };
layout(std430) writeonly buffer OutBuffer { vec4 ys[]; };
layout(push_constant) uniform Params { uint count; } pc;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    float x = xs[i];
    ys[i] = vec4(cos(x * 3.14159265), sin(x * 3.14159265), acos(2.0 * x - 1.0), atan(2.0 * x - 1.0, 0.3));
}
