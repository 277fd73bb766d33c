#version 460
// PoissonReconstruct, multigrid: x_fine += P x_coarse (bilinear, poisson_transfer.glsl).
#include "passes/gradient_domain/poisson_common.glsl"
#include "passes/gradient_domain/poisson_transfer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 fineSize;
    uvec2 coarseSize;
    uint xOffset;        // fine
    uint coarseOffset;   // coarse x
    uint slot;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 f = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(f), pc.fineSize))) return;
    ivec2 nc = ivec2(pc.coarseSize);
    ivec2 parent = f >> 1;
    ivec2 other = clamp(parent + mix(ivec2(-1), ivec2(1), notEqual(f & 1, ivec2(0))), ivec2(0), nc - 1);
    vec4 sum = vec4(0.0);
    for (int j = 0; j < 2; ++j) {
        int cy = j == 0 ? parent.y : other.y;
        if (j == 1 && other.y == parent.y) break;
        float wy = poisson_prolong_weight(f.y, cy, nc.y);
        for (int k = 0; k < 2; ++k) {
            int cx = k == 0 ? parent.x : other.x;
            if (k == 1 && other.x == parent.x) break;
            float wx = poisson_prolong_weight(f.x, cx, nc.x);
            sum += (wx * wy) * vec[pc.coarseOffset + uint(cy) * pc.coarseSize.x + uint(cx)];
        }
    }
    vec[pc.xOffset + poisson_index(f, pc.fineSize)] += sum;
}
