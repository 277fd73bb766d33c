#version 460
// PoissonReconstruct: r = b - A x on one level. On the finest level it starts a linear solve
// (partial sums of r.r and b.b); multigrid levels use it before restriction.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 levelSize;
    uint xOffset;
    uint bOffset;
    uint rOffset;
    uint wOffset;
    uint slot;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    vec4 r = vec4(0.0), b = vec4(0.0);
    if (all(lessThan(uvec2(p), pc.levelSize))) {
        uint i = poisson_index(p, pc.levelSize);
        b = vec[pc.bOffset + i];
        r = b - poisson_apply(pc.xOffset, pc.wOffset, pc.levelSize, p);
        vec[pc.rOffset + i] = r;
    }
    poisson_group_sum(r * r, b * b);
}
