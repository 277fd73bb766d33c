#version 460
// ErrorMetric, stage 2: mean of the per-pixel errors in one workgroup (Kahan sums per thread,
// then a shared-memory tree), written to result[0].
layout(local_size_x = 256) in;
layout(r32f) uniform readonly image2D perPixelImage;
layout(std430) writeonly buffer Result { float result[]; };
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

shared float partial[256];

void main() {
    uint t = gl_LocalInvocationID.x;
    float sum = 0.0, comp = 0.0;
    for (uint y = t; y < pc.frameSize.y; y += 256u) {
        float row = 0.0;
        for (uint x = 0u; x < pc.frameSize.x; ++x) row += imageLoad(perPixelImage, ivec2(x, y)).r;
        float yk = row - comp;
        float tk = sum + yk;
        comp = (tk - sum) - yk;
        sum = tk;
    }
    partial[t] = sum;
    barrier();
    for (uint s = 128u; s > 0u; s >>= 1) {
        if (t < s) partial[t] += partial[t + s];
        barrier();
    }
    if (t == 0u) result[0] = partial[0] / float(pc.frameSize.x * pc.frameSize.y);
}
