#version 460
// PoissonReconstruct: scales the finest level's weights to mean 1 (after poisson_rhs read
// them unscaled: scaling in place there would race with the neighbours' reads).
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint weightSlot;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    vec2 sums = steps[pc.weightSlot].rr.xy;
    weight[poisson_index(p, pc.frameSize)] *= sums.y / max(sums.x, 1e-30);
}
