#version 460
// PoissonReconstruct, CG: q = A p and the partial sums of p.q.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint slot;
    uint pOffset;
    uint qOffset;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    vec4 pq = vec4(0.0);
    if (all(lessThan(uvec2(p), pc.frameSize))) {
        uint i = poisson_index(p, pc.frameSize);
        vec4 q = poisson_apply(pc.pOffset, 0u, pc.frameSize, p);
        vec[pc.qOffset + i] = q;
        pq = vec[pc.pOffset + i] * q;
    }
    poisson_group_sum(pq, vec4(0.0));
}
