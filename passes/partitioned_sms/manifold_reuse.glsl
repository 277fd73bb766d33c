// What ManifoldReSTIRTemporal and ManifoldReSTIRSpatial share (Hong et al. 2025 Sec. 5): the
// reservoir buffers, the shift counters, and the end of a reuse kernel (the reservoir, the
// caustic it estimates, F W, and with the path tracer's part the full image).
#ifndef LOOM_PASSES_MANIFOLD_REUSE_GLSL
#define LOOM_PASSES_MANIFOLD_REUSE_GLSL

#include "lib/manifold/shift.glsl"
#include "lib/mis.glsl"
#include "lib/rng.glsl"

layout(std430) readonly buffer ReservoirsIn {
    ManifoldReservoirHeader header_in;
    ManifoldReservoir reservoirs_in[];
};
layout(std430) writeonly buffer ReservoirsOut {
    ManifoldReservoirHeader header_out;
    ManifoldReservoir reservoirs_out[];
};
layout(std430) buffer ManifoldReuseCounters {
    uint reuse_attempts;     // shifts tried
    uint reuse_success;      // of which succeeded
    uint reuse_back_failed;  // failed at the walk back (bijectivity)
    uint reuse_rays;
    uint reuse_max_steps;    // BVH steps of one invocation (lavapipe's loop limit)
};
#if HAS_CAUSTIC
layout(rgba32f) uniform writeonly image2D causticImage;
#endif
#if HAS_PATH
layout(rgba32f) uniform readonly image2D pathImage;
layout(rgba32f) uniform writeonly image2D colorImage;
#endif

ManifoldShiftSettings manifold_reuse_settings(uint constraint, uint iterations, float threshold,
                                              float uniqueness, float min_segment,
                                              uint max_chain, float clamp, uint bijective) {
    ManifoldShiftSettings ss;
    ss.ms.constraint = constraint;
    ss.ms.max_iterations = iterations;
    ss.ms.solver_threshold = threshold;
    ss.ms.min_segment = min_segment;
    ss.ms.step_control = MANIFOLD_STEP_REPROJECTION;  // the reference rule
    ss.ms.max_chain = min(max_chain, uint(MANIFOLD_MAX_VERTICES));
    ss.uniqueness_threshold = uniqueness;
    ss.geometric_clamp = clamp;
    ss.bijective = bijective != 0u;
    return ss;
}

// The resampled reservoir's weight W = w_sum / p_hat(Y) (0 without a sample).
void manifold_reservoir_finalize(inout ManifoldReservoir r, float w_sum) {
    r.weight.x = r.F.w > 0.0 ? w_sum / r.F.w : 0.0;
    if (!(r.weight.x > 0.0) || isinf(r.weight.x)) {
        r.weight.x = 0.0;
        r.F = vec4(0.0);
    }
}

void manifold_reuse_finish(uvec2 pixel, uint index, ManifoldReservoir r, uint attempts,
                           uint success) {
    reservoirs_out[index] = r;
    vec3 caustic = r.F.rgb * r.weight.x;
#if HAS_CAUSTIC
    imageStore(causticImage, ivec2(pixel), vec4(caustic, 1.0));
#endif
#if HAS_PATH
    imageStore(colorImage, ivec2(pixel),
               vec4(imageLoad(pathImage, ivec2(pixel)).rgb + caustic, 1.0));
#endif
    if (attempts > 0u) {
        atomicAdd(reuse_attempts, attempts);
        atomicAdd(reuse_success, success);
        atomicAdd(reuse_back_failed, manifold_shift_back_failed);
        atomicAdd(reuse_rays, manifold_shift_rays);
        atomicMax(reuse_max_steps, bvh_iterations);
    }
}

#endif
