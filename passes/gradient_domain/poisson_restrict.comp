#version 460
// PoissonReconstruct, multigrid: b_coarse = R r_fine with R = P^T / 4 (poisson_transfer.glsl),
// gathered over the 4x4 fine cells whose interpolation uses this coarse cell. The fine
// residual comes from poisson_smooth's residual mode, zero on the black cells ((x + y) odd):
// those are skipped.
#include "passes/gradient_domain/poisson_common.glsl"
#include "passes/gradient_domain/poisson_transfer.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 fineSize;
    uvec2 coarseSize;
    uint rOffset;   // fine residual
    uint bOffset;   // coarse right-hand side
    uint slot;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 c = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(c), pc.coarseSize))) return;
    ivec2 nf = ivec2(pc.fineSize), nc = ivec2(pc.coarseSize);
    vec4 sum = vec4(0.0);
    for (int fy = max(2 * c.y - 1, 0); fy <= min(2 * c.y + 2, nf.y - 1); ++fy) {
        float wy = poisson_prolong_weight(fy, c.y, nc.y);
        if (wy == 0.0) continue;
        int first = max(2 * c.x - 1, 0);
        first += (first + fy) & 1;  // the first red cell of the row
        for (int fx = first; fx <= min(2 * c.x + 2, nf.x - 1); fx += 2) {
            float wx = poisson_prolong_weight(fx, c.x, nc.x);
            if (wx != 0.0) sum += (wx * wy) * vec[pc.rOffset + uint(fy) * pc.fineSize.x + uint(fx)];
        }
    }
    vec[pc.bOffset + poisson_index(c, pc.coarseSize)] = 0.25 * sum;
}
