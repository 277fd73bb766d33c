#version 460
// MNEEDimReduction, stage 1: the reference path tracer without the paths the caustic estimate
// covers (receiver -> one caster vertex -> caustic emitter, manifold/coverage.glsl, with the
// estimate's receiver rule).
#include "lib/camera.glsl"
#include "lib/integrator/path.glsl"
#include "lib/rng.glsl"
#include "passes/mnee_dr/mnee_dr_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D pathImage;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    vec3 o, d;
    Rng rng = mnee_dr_camera_ray(pixel, o, d);
    PathSettings ps;
    ps.max_bounces = pc.maxBounces;
    ps.rr_depth = pc.rrDepth;
    ps.mis_heuristic = pc.misHeuristic;
    ps.nee = true;
    ps.mis = true;
    ps.covered_max_chain = pc.excludeCovered != 0u ? 1u : 0u;
    ps.covered_depth = pc.receiverDepth;
    Hit none;
    none.t = 0.0;
    none.prim = ~0u;
    none.bary = vec2(0.0);
    PathRadiance pr = path_trace(o, d, false, none, false, ps, rng);
    imageStore(pathImage, ivec2(pixel), vec4(pr.L, 1.0));
    atomicAdd(mnee_dr_counters[COUNTER_RAYS], pr.rays);
    atomicMax(mnee_dr_counters[COUNTER_MAX_STEPS], bvh_iterations);
}
