#version 460
// PoissonReconstruct: one solver step's update of x and r, with the partial sums of the new
// r.r.
//   CG:     alpha = (r.z)_k / (p.Ap)_k;  x += alpha p;  r -= alpha A p.
//   Jacobi: x += D^-1 r (r = b - A x from poisson_residual); no r update (the next step
//           recomputes it), so no partial sums either.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint slot;
    uint jacobi;
    uint xOffset;
    uint rOffset;
    uint pOffset;
    uint qOffset;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    bool inside = all(lessThan(uvec2(p), pc.frameSize));
    uint i = inside ? poisson_index(p, pc.frameSize) : 0u;
    if (pc.jacobi != 0u) {
        if (inside) vec[pc.xOffset + i] += vec[pc.rOffset + i] / poisson_diagonal(0u, pc.frameSize, p);
        return;
    }
    vec4 r = vec4(0.0);
    if (inside) {
        vec4 alpha = poisson_ratio(steps[pc.slot].rz, steps[pc.slot].pAp);
        vec[pc.xOffset + i] += alpha * vec[pc.pOffset + i];
        r = vec[pc.rOffset + i] - alpha * vec[pc.qOffset + i];
        vec[pc.rOffset + i] = r;
    }
    poisson_group_sum(r * r, vec4(0.0));
}
