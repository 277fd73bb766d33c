// What the three SpecularManifoldSampling kernels share: their parameters (filled by name from
// the pass's declaration), the per-pixel estimator state that carries an estimate across
// dispatches, and the frame's counters. Layouts mirrored by SpecularManifoldSamplingPass.cpp.
#ifndef LOOM_PASSES_SMS_COMMON_GLSL
#define LOOM_PASSES_SMS_COMMON_GLSL

#include "lib/manifold/sms.glsl"
#include "lib/work_list.glsl"

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint estimator;            // ESTIMATOR_UNBIASED / _BIASED / _MNEE
    uint constraint;           // MANIFOLD_CONSTRAINT_*
    uint stepControl;          // MANIFOLD_STEP_*
    uint maxIterations;
    float solverThreshold;
    float uniquenessThreshold;
    uint maxTrials;
    uint trialCap;             // TRIAL_CAP_DROP / _KEEP
    uint biasedTrials;         // M
    uint maxChain;
    float geometricTermClamp;  // 0 = off
    uint maxBounces;
    uint rrDepth;
    uint misHeuristic;
    uint excludeCovered;
    uint receiverDepth;        // SMS at the first smooth vertex behind at most this many specular ones
    uint stepBudget;           // BVH steps an invocation may start a new trial below
    float minSegment;          // world units (pass: 1e-4 x scene radius)
    uint dispatchIndex;        // sms_trials.comp: which of the frame's trial dispatches
} pc;

const uint SMS_NONE = 0u;       // no SMS estimate at this pixel
const uint SMS_FIRST = 1u;      // looking for the solution of the sample's own seed
const uint SMS_BERNOULLI = 2u;  // unbiased: trials until that solution is found again
const uint SMS_BIASED = 3u;     // biased: M trials, unique solutions summed
const uint SMS_DONE = 4u;

struct SmsPixel {
    uvec4 hit;     // x0: x prim, yz barycentrics (bits), w status
    vec4 wo;       // xyz direction from x0 towards the camera
    uvec4 rng;     // the SMS random stream (seeds)
    vec4 light_y;  // xyz light point, w pdf
    vec4 light_n;  // xyz area light normal (0: point light), w light index (bits)
    vec4 target;   // xyz the solution's first direction (unbiased), w trials so far (K)
    vec4 value;    // rgb the estimate (unbiased: the solution's contribution), w solutions
    uvec4 counts;  // x Newton iterations, y trials, z solution found, w trial cap reached
    vec4 beta;     // rgb the camera path's throughput up to x0 (1 at a primary receiver)
};
layout(std430) buffer SmsPixels { SmsPixel sms_pixels[]; };
// Biased SMS: the directions of the unique solutions found so far (biasedTrials <= 32).
#define SMS_MAX_BIASED_TRIALS 32
struct SmsSolutionSet {
    vec4 dirs[SMS_MAX_BIASED_TRIALS];
};
layout(std430) buffer SmsSolutions { SmsSolutionSet sms_solutions[]; };

// MNEE's seeds: [0].x = 1 when a refractive caster exists, then the bounding-box centre of each
// reflective caster (SpecularManifoldSamplingPass.cpp).
layout(std430) readonly buffer SmsMneeSeeds { vec4 sms_mnee_seeds[]; };

// Frame totals (Hong et al. 2025 Table 1 columns are ratios of these).
layout(std430) buffer SmsCounters {
    uint sms_samples;      // SMS estimates started (receivers with a light sample)
    uint sms_solved;       // of which found a solution (the first walk or any of M)
    uint sms_iterations;   // Newton steps over all walks, failed ones included
    uint sms_trials;       // walks over all estimates (the first one included)
    uint sms_bernoulli;    // Bernoulli trials of the unbiased estimates that found one
    uint sms_capped;       // estimates that reached maxTrials or ran out of dispatches
    uint sms_max_bvh_iterations;
    uint sms_rays;
};

// The estimate at the pixel's i-th receiver (MANIFOLD_MAX_RECEIVERS slots per pixel).
uint sms_slot(uvec2 p, uint i) {
    return (p.y * pc.frameSize.x + p.x) * uint(MANIFOLD_MAX_RECEIVERS) + i;
}

ManifoldSettings sms_settings() {
    ManifoldSettings ms;
    ms.constraint = pc.constraint;
    ms.step_control = pc.stepControl;
    ms.max_iterations = pc.maxIterations;
    ms.solver_threshold = pc.solverThreshold;
    ms.min_segment = pc.minSegment;
    ms.max_chain = min(pc.maxChain, uint(MANIFOLD_MAX_VERTICES));
    return ms;
}

ManifoldLight sms_pixel_light(SmsPixel st) {
    return manifold_light_from(st.light_y.xyz, st.light_y.w, st.light_n.xyz,
                               floatBitsToUint(st.light_n.w));
}

#endif
