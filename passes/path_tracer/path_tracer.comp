#version 460
// Reference unidirectional path tracer: BSDF sampling and next-event estimation combined by
// MIS (Veach 1997), Russian roulette, thin lens, motion blur over the shutter. The baseline
// every other estimator is tested against, so each strategy can be switched off. This is the
// megakernel schedule: one invocation runs a pixel's paths from camera to end.
#include "passes/path_tracer/path_tracer_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    Rng rng = pt_rng(pixel);
    PathSettings ps = pt_path_settings();
    PtPixelSums sums = pt_sums_none();
    uint rays = 0u;
    for (uint s = 0u; s < pc.dispatchSamples; ++s) {
        vec3 o, d;
        bool given, first_found;
        Hit first;
        pt_camera_sample(pixel, s, rng, o, d, given, first, first_found);
        PathRadiance pr = path_trace(o, d, given, first, first_found, ps, rng);
        rays += pr.rays;
        pt_sums_add(sums, pr);
    }
    atomicAdd(ray_count, rays);
    atomicMax(max_bvh_iterations, bvh_iterations);
    pt_store(pixel, sums);
}
