#version 460
// PoissonReconstruct, multigrid: the next coarser level's operator by rediscretisation. The
// screening s is the children's mean; a coarse edge's weight is the mean of the fine edges
// crossing the same face, divided by 4 (the grid spacing doubles: a Laplacian in pixel units
// shrinks by 4, the screening does not).
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 fineSize;
    uvec2 coarseSize;
    uint fineOffset;
    uint coarseOffset;
} pc;

void main() {
    ivec2 c = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(c), pc.coarseSize))) return;
    ivec2 nf = ivec2(pc.fineSize);
    float s = 0.0, n = 0.0, wx = 0.0, nx = 0.0, wy = 0.0, ny = 0.0;
    for (int j = 0; j < 2; ++j)
        for (int k = 0; k < 2; ++k) {
            ivec2 f = 2 * c + ivec2(k, j);
            if (any(greaterThanEqual(f, nf))) continue;
            vec4 w = weight[pc.fineOffset + uint(f.y) * pc.fineSize.x + uint(f.x)];
            s += w.x;
            n += 1.0;
            if (k == 1) { wx += w.y; nx += 1.0; }
            if (j == 1) { wy += w.z; ny += 1.0; }
        }
    bool right = uint(c.x) + 1u < pc.coarseSize.x, below = uint(c.y) + 1u < pc.coarseSize.y;
    weight[pc.coarseOffset + poisson_index(c, pc.coarseSize)] =
        vec4(s / n, right && nx > 0.0 ? 0.25 * wx / nx : 0.0, below && ny > 0.0 ? 0.25 * wy / ny : 0.0, 0.0);
}
