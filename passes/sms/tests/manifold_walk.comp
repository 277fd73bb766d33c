#version 460
// Test kernel (passes/sms/tests/test_sms.cpp): one manifold trial (seed chain, Newton walk with
// re-projection, visibility) against the loaded scene. Input rows, per column: 0 x0, 1 its
// geometric normal, 2 y (light point), 3 ny (area light normal, 0: point light; w = 1: y is a direction, a directional light), 4 seed point
// (w = 1: straight line to y, MNEE), 5 (constraint, max iterations, threshold, max chain),
// 6/7 es/et (the end point's plane; 6.w the step control). Output rows: 0 (phase, iterations, k, endpoint det),
// 1..4 chain vertices (w = triangle), 5 (beta, error of the final chain, 0, 0), 6 the first
// vertex's geometric normal.
#include "lib/bvh.glsl"
#include "lib/manifold/sms.glsl"

layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

vec4 row(int x, int y) { return imageLoad(inputImage, ivec2(x, y)); }

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= int(pc.frameSize.x)) return;
    vec4 cfg = row(x, 5);
    ManifoldSettings ms;
    ms.constraint = uint(cfg.x);
    ms.max_iterations = uint(cfg.y);
    ms.solver_threshold = cfg.z;
    ms.min_segment = 1e-5;
    ms.step_control = uint(row(x, 6).w);
    ms.max_chain = uint(cfg.w);
    ManifoldTrial tr = manifold_trial_start(row(x, 0).xyz, row(x, 1).xyz, row(x, 2).xyz,
                                            row(x, 3).xyz, row(x, 6).xyz, row(x, 7).xyz,
                                            row(x, 3).w != 0.0, row(x, 4).w != 0.0, row(x, 4).xyz);
    for (uint n = 0u; n < 400u && manifold_trial_running(tr); ++n) {
        Hit hit;
        bool found = trace_closest(tr.ray_o, tr.ray_d, tr.ray_tmin, tr.ray_tmax, BVH_MASK_ALL, hit);
        manifold_trial_advance(tr, found, hit, ms);
    }
    imageStore(outputImage, ivec2(x, 0), vec4(float(tr.phase), float(tr.iterations),
                                            float(tr.chain.k), tr.endpoint_det));
    for (uint i = 0u; i < 4u; ++i)
        imageStore(outputImage, ivec2(x, 1 + int(i)),
                   i < tr.chain.k ? vec4(tr.chain.v[i].p, float(tr.chain.v[i].prim)) : vec4(0.0));
    float e = tr.chain.k > 0u ? manifold_chain_error(ms.constraint, tr.chain, tr.x0, tr.y) : -1.0;
    imageStore(outputImage, ivec2(x, 5), vec4(tr.beta, e, 0.0, 0.0));
    imageStore(outputImage, ivec2(x, 6), tr.chain.k > 0u ? vec4(tr.chain.v[0].ng, 0.0) : vec4(0.0));
}
