#version 460
// SpecularManifoldSampling, stage 2: the walks of each pixel's estimate (Zeltner et al. 2020
// Sec. 4.3-4.5), continued over dispatches. A dispatch starts trials while the invocation has
// run fewer than stepBudget BVH steps (lavapipe ends every loop at 65535 iterations per
// invocation) and keeps the estimate's state in SmsPixels for the next one.
//   unbiased: the seed's own walk; if it converges, Bernoulli trials with fresh seeds until one
//             finds the same solution; the estimate is its contribution times the count K,
//             E[K] = 1 / p (Sec. 4.5). At maxTrials: dropped (reference code) or kept (trialCap).
//   biased:   M = biasedTrials walks, each unique solution's contribution once (Sec. 4.5).
//   mnee:     one walk from the straight line to the light (Hanika et al. 2015), or, for a
//             reflective caster, from its bounding-box centre (the reference code's seed: a
//             straight line never reflects); one of these seeds per estimate, chosen uniformly
//             and weighted by their number.
#include "lib/manifold/sms.glsl"
#include "lib/rng.glsl"
#include "passes/sms/sms_common.glsl"

// 8 x 8 invocations indexed linearly: with a 1D local size (64 or 8) lavapipe ran the walks
// of only the first few groups (measured: 130-180 of ~4700 walks at 64 x 64).
layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    // Invocation i takes the i-th active pixel (lib/work_list.glsl); the dispatch is indirect.
    uint d = pc.dispatchIndex, index;
    if (!work_list_item(d, gl_WorkGroupID.x * WORK_LIST_GROUP + gl_LocalInvocationIndex, index))
        return;
    SmsPixel st = sms_pixels[index];
    uint status = st.hit.w;
    if (status == SMS_NONE || status == SMS_DONE) return;

    Hit h0;
    h0.prim = st.hit.x;
    h0.bary = uintBitsToFloat(st.hit.yz);
    h0.t = 0.0;
    ShadingPoint sh0 = shading_point(h0);
    vec3 wo = shading_to_local(sh0, st.wo.xyz);
    ManifoldLight ml = sms_pixel_light(st);
    ManifoldSettings ms = sms_settings();
    Rng rng = rng_from_seed(st.rng);
    ManifoldReceiver rc = manifold_receiver(sh0, st.wo.xyz, ml);
    uint iterations = 0u, trials = 0u, bernoulli = 0u, capped = 0u, rays = 0u, solutions = 0u;

    ManifoldTrial tr;
    tr.phase = TRIAL_FAILED;
    float seed_weight = 1.0;  // MNEE: the number of seed choices
    bool pending = false;  // tr holds a finished trial not yet accounted for
    for (;;) {
        if (!manifold_trial_running(tr)) {
            if (pending) {
                pending = false;
                iterations += tr.iterations;
                bool ok = tr.phase == TRIAL_CONVERGED;
                // One contribution call site (SMS_FIRST, or a unique biased solution).
                bool wanted = ok && status != SMS_BERNOULLI;
                vec3 dir = ok ? manifold_trial_direction(tr) : vec3(0.0);
                uint found = uint(st.value.w);
                if (wanted && status == SMS_BIASED)
                    for (uint j = 0u; j < found; ++j)
                        wanted = wanted && !manifold_same_solution(dir, sms_solutions[index].dirs[j].xyz,
                                                                   pc.uniquenessThreshold);
                vec3 value = wanted ? seed_weight * manifold_trial_contribution(
                                                        tr, ms, sh0, wo, ml, pc.geometricTermClamp)
                                    : vec3(0.0);
                if (status == SMS_FIRST) {
                    if (!ok) {
                        status = SMS_DONE;
                    } else {
                        st.value.rgb = value;
                        st.target = vec4(dir, 1.0);
                        st.counts.z = 1u;
                        solutions += 1u;
                        status = pc.estimator == ESTIMATOR_UNBIASED ? SMS_BERNOULLI : SMS_DONE;
                        if (!any(greaterThan(st.value.rgb, vec3(0.0)))) status = SMS_DONE;
                    }
                } else if (status == SMS_BERNOULLI) {
                    bernoulli += 1u;
                    if (ok && manifold_same_solution(dir, st.target.xyz, pc.uniquenessThreshold)) {
                        st.value.rgb *= st.target.w;
                        status = SMS_DONE;
                    } else {
                        st.target.w += 1.0;
                        if (st.target.w >= float(pc.maxTrials)) {
                            capped += 1u;
                            st.counts.w = 1u;
                            if (pc.trialCap == TRIAL_CAP_DROP) st.value.rgb = vec3(0.0);
                            else st.value.rgb *= st.target.w;
                            status = SMS_DONE;
                        }
                    }
                } else {  // SMS_BIASED
                    st.target.w += 1.0;
                    if (wanted) {  // a solution not found before
                        sms_solutions[index].dirs[found] = vec4(dir, 0.0);
                        st.value.rgb += value;
                        st.value.w += 1.0;
                        if (found == 0u) {
                            st.counts.z = 1u;
                            solutions += 1u;
                        }
                    }
                    if (st.target.w >= float(pc.biasedTrials)) status = SMS_DONE;
                }
            }
            if (status == SMS_DONE || bvh_iterations >= pc.stepBudget) break;
            // The next trial: a fresh seed on the casters, or MNEE's (the straight line, or a
            // reflector's centre).
            vec3 u = vec3(rng_next2(rng), rng_next(rng));
            bool straight = pc.estimator == ESTIMATOR_MNEE;
            vec3 seed = straight ? ml.y : manifold_sample_caster(u);
            if (straight) {
                uint line = sms_mnee_seeds[0].x != 0.0 ? 1u : 0u;
                uint choices = uint(sms_mnee_seeds.length()) - 1u + line;
                uint k = min(uint(u.z * float(choices)), choices - 1u);
                seed_weight = float(choices);
                if (k >= line) {
                    straight = false;
                    seed = sms_mnee_seeds[1u + k - line].xyz;
                }
            }
            tr = manifold_trial_start(rc.x0, rc.ng0, ml.y, ml.n, rc.es, rc.et, ml.directional, straight,
                                      seed);
#ifdef MANIFOLD_ROUGH_CASTERS
            // One set of offset normals per estimate (its own stream: xyz of the SMS stream,
            // which the trials leave unchanged, with z mixed).
            tr.offset_stream = uvec4(st.rng.xy, st.rng.z ^ 0x0FF5E7A1u, 0u);
#endif
            trials += 1u;
            pending = true;
        }
        Hit hit;
        bool found = trace_closest(tr.ray_o, tr.ray_d, tr.ray_tmin, tr.ray_tmax, BVH_MASK_ALL, hit);
        rays += 1u;
        manifold_trial_advance(tr, found, hit, ms);
    }
    st.hit.w = status;
    if (status != SMS_DONE) work_list_append(d + 1u, index);
    st.rng = rng.state;
    st.counts.x += iterations;
    st.counts.y += trials;
    sms_pixels[index] = st;
    atomicAdd(sms_iterations, iterations);
    atomicAdd(sms_trials, trials);
    atomicAdd(sms_bernoulli, bernoulli);
    atomicAdd(sms_capped, capped);
    atomicAdd(sms_solved, solutions);
    atomicAdd(sms_rays, rays);
    atomicMax(sms_max_bvh_iterations, bvh_iterations);
}
