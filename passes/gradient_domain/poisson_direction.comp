#version 460
// PoissonReconstruct, CG: p = z + beta p, beta = (r.z)_k / (r.z)_(k-1); p = z on a solve's
// first step. No dot product here: poisson_apply sums p.Ap right after.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint slot;       // step k
    uint first;      // 1 on a solve's first step
    uint zOffset;
    uint pOffset;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    uint i = poisson_index(p, pc.frameSize);
    vec4 beta = pc.first != 0u ? vec4(0.0) : poisson_ratio(steps[pc.slot].rz, steps[pc.slot - 1u].rz);
    vec[pc.pOffset + i] = vec[pc.zOffset + i] + beta * (pc.first != 0u ? vec4(0.0) : vec[pc.pOffset + i]);
}
