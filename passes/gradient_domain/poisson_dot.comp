#version 460
// PoissonReconstruct, preconditioned CG: the partial sums of r.z after the V-cycle.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint slot;
    uint aOffset;
    uint bOffset;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    vec4 ab = vec4(0.0);
    if (all(lessThan(uvec2(p), pc.frameSize))) {
        uint i = poisson_index(p, pc.frameSize);
        ab = vec[pc.aOffset + i] * vec[pc.bOffset + i];
    }
    poisson_group_sum(ab, vec4(0.0));
}
