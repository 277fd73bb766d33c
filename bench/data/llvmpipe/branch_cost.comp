#version 460
// bench/llvmpipe_costs.sh: what a branch costs on the device. `work` selects who runs a fixed
// block of ALU work (`steps` dependent iterations): 0 nobody (no branch), 1 every invocation
// (no branch), 2 nobody, behind a branch on a push constant (uniform, known false), 3 nobody,
// behind a branch on a value computed per invocation that is always false, 4 every other
// invocation (divergent inside each 8-wide SIMD batch), 5 every other batch of 8 (coherent).
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D colorImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    int work;
    int steps;
} pc;

float block(float x) {
    for (int i = 0; i < pc.steps; ++i) x = sin(x * 1.37 + 0.11) * 0.9 + cos(x);
    return x;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    float x = float(p.x) * 0.001 + float(p.y) * 0.002 + float(pc.frameIndex);
    float y = x;
    if (pc.work == 1) {
        y = block(x);
    } else if (pc.work == 2) {
        if (pc.steps < 0) y = block(x);
    } else if (pc.work == 3) {
        if (x < -1.0) y = block(x);
    } else if (pc.work == 4) {
        if ((p.x & 1) == 0) y = block(x);
    } else if (pc.work == 5) {
        if (((p.x >> 3) & 1) == 0) y = block(x);
    }
    imageStore(colorImage, p, vec4(y, x, 0.0, 1.0));
}
