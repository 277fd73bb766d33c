#version 460
// PoissonReconstruct: the residual history as a plot for the inspector. x: solver steps in
// order (every linear solve of an L1 run one after the other); y: log10 of the relative
// residual ||r|| / ||b|| (worst channel), from 10^0 at the top to 10^-8 at the bottom, with a
// grid line per decade. Steps never reached (converged earlier) are left empty.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D plotImage;
layout(push_constant) uniform Params {
    uvec2 plotSize;
    uint solves;       // linear solves (1 for L2, IRLS iterations for L1)
    uint stepsPerSolve;  // records per solve: the weights record, then steps 0..iterations
} pc;

float relative(uint slot, uint solveStart) {
    vec4 rr = steps[slot].rr, bb = steps[solveStart].bb;
    vec3 rel = rr.rgb / max(bb.rgb, vec3(1e-30));
    return sqrt(max(max(rel.r, rel.g), rel.b));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.plotSize))) return;
    vec3 colour = vec3(0.08);
    float decade = float(pc.plotSize.y - 1u) / 8.0;
    if (mod(float(p.y), decade) < 1.0) colour = vec3(0.25);
    uint perSolve = pc.stepsPerSolve - 1u;
    uint total = pc.solves * perSolve;
    // The steps this column covers: the curve spans them so no step falls between columns.
    uint a = uint(p.x) * total / pc.plotSize.x, b = max(a + 1u, uint(p.x + 1) * total / pc.plotSize.x);
    float lo = 1e30, hi = -1e30;
    for (uint k = a; k < b && k < total; ++k) {
        uint solve = k / perSolve, start = solve * pc.stepsPerSolve + 1u, slot = start + k % perSolve;
        if (k % perSolve != 0u && steps[slot - 1u].info.x == 0u) continue;  // not reached
        float y = -log(max(relative(slot, start), 1e-12)) / log(10.0) * decade;
        lo = min(lo, y);
        hi = max(hi, y);
    }
    if (lo <= hi && float(p.y) >= lo - 1.0 && float(p.y) <= hi + 1.0) colour = vec3(1.0, 0.8, 0.2);
    imageStore(plotImage, p, vec4(colour, 1.0));
}
