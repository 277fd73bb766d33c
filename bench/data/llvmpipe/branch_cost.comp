#version 460
// bench/llvmpipe_costs.sh: what a branch costs on the device. WORK (a define) selects who runs a fixed
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
#ifndef BLOCK_SHAPE
#define BLOCK_SHAPE 0
#endif
#ifndef WORK
#define WORK 0
#endif

#define STEP(x) x = sin(x * 1.37 + 0.11) * 0.9 + cos(x);
#define STEP4(x) STEP(x) STEP(x) STEP(x) STEP(x)
#define STEP16(x) STEP4(x) STEP4(x) STEP4(x) STEP4(x)
#define STEP64(x) STEP16(x) STEP16(x) STEP16(x) STEP16(x)

float block(float x) {
#if BLOCK_SHAPE == 0
    for (int i = 0; i < pc.steps; ++i) STEP(x)
#else
    STEP64(x) STEP64(x)
#endif
    return x;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    float x = float(p.x) * 0.001 + float(p.y) * 0.002 + float(pc.frameIndex);
    float y = x;
    // WORK (a define, like BLOCK_SHAPE: a run-time if-chain over the cases would run every
    // case's straight-line copy of the block); the push constant `work` mirrors it.
#if WORK == 1
    y = block(x);
#elif WORK == 2
    if (pc.steps < 0) y = block(x);
#elif WORK == 3
    if (x < -1.0) y = block(x);
#elif WORK == 4
    if ((p.x & 1) == 0) y = block(x);
#elif WORK == 5
    if (((p.x >> 3) & 1) == 0) y = block(x);
#endif
    imageStore(colorImage, p, vec4(y, x, 0.0, 1.0));
}
