#version 460
// PartitionedSMS, stage 2 (Hong et al. 2025 Sec. 4.1): the initial walk from a seed drawn by
// Eq. 7 and bounded by its trust region, then Bernoulli trials drawn from the conditional
// space C(u*) (Eq. 9) until one finds the same solution; the unbiased contribution weight is
// K / P(C(u*)) (Eq. 8). The initial walk and every trial run the identical solver
// (manifold_trial_* with MANIFOLD_TRUST_REGION). Continued over dispatches like
// SpecularManifoldSampling's trials (lib/work_list.glsl).
#include "passes/partitioned_sms/psms_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    uint d = pc.dispatchIndex, index;
    if (!work_list_item(d, gl_WorkGroupID.x * WORK_LIST_GROUP + gl_LocalInvocationIndex, index))
        return;
    PsmsPixel st = psms_pixels[index];
    uint status = st.hit.w;
    if (status == PSMS_NONE || status == PSMS_DONE) return;
    uvec2 pixel = uvec2(index % pc.frameSize.x, index / pc.frameSize.x);

    Hit h0;
    h0.prim = st.hit.x;
    h0.bary = uintBitsToFloat(st.hit.yz);
    h0.t = 0.0;
    ShadingPoint sh0 = shading_point(h0);
    vec3 wo = shading_to_local(sh0, st.wo.xyz);
    ManifoldLight ml = manifold_light_from(st.light_y.xyz, st.light_y.w, st.light_n.xyz,
                                           floatBitsToUint(st.light_n.w));
    ManifoldSettings ms = psms_settings();
    ManifoldReceiver rc = manifold_receiver(sh0, st.wo.xyz, ml);
    uint caster = manifold_pair_caster(st.pair.x);
    ManifoldSeedSpace space = manifold_seed_space(rc.x0, rc.ng0, manifold_caster_bound(caster));
    ManifoldPartition part = psms_partition(st, pixel);
    Rng rng = rng_from_seed(st.rng);
    uint iterations = 0u, walks = 0u, bernoulli = 0u, capped = 0u, rays = 0u, solutions = 0u;

    ManifoldTrial tr;
    tr.phase = TRIAL_FAILED;
    bool pending = false;  // tr holds a finished walk not yet accounted for
    for (;;) {
        if (!manifold_trial_running(tr)) {
            if (pending) {
                pending = false;
                iterations += tr.iterations;
                bool ok = tr.phase == TRIAL_CONVERGED;
                vec3 dir = ok ? manifold_trial_direction(tr) : vec3(0.0);
                if (status == PSMS_FIRST) {
                    vec3 value = ok ? manifold_trial_contribution(tr, ms, sh0, wo, ml,
                                                                  pc.geometricTermClamp)
                                    : vec3(0.0);
                    vec2 u_star;
                    if (!ok || !any(greaterThan(value, vec3(0.0))) ||
                        !manifold_seed_coords(space, dir, u_star)) {
                        status = PSMS_DONE;
                        st.value.rgb = vec3(0.0);
                        st.x1.w = 0.0;
                    } else {
                        // C(u*) = R(u*): its tiles in I, and P(C) (Eq. 8).
                        uvec2 centre = manifold_seed_tile(u_star, pc.tiles);
                        uint in_region = partition_region_in_set(part, centre);
                        st.pair.w = centre.x | (centre.y << 8u) | (in_region << 16u);
                        st.wo.w = partition_region_probability(part, in_region);
                        st.value.rgb = value;
                        st.target = vec4(dir, 1.0);
                        st.x1 = vec4(tr.chain.v[0].p, 0.0);
                        for (uint j = 0u; j < 4u; ++j)
                            st.shapes[j] = j < tr.chain.k ? tr.chain.v[j].shape : MANIFOLD_NO_SHAPE;
                        st.counts.z = 1u;
                        solutions += 1u;
                        status = PSMS_BERNOULLI;
                    }
                } else {  // PSMS_BERNOULLI
                    bernoulli += 1u;
                    if (ok && manifold_same_solution(dir, st.target.xyz, pc.uniquenessThreshold)) {
                        st.x1.w = st.target.w / st.wo.w;
                        status = PSMS_DONE;
                    } else {
                        st.target.w += 1.0;
                        if (st.target.w >= float(pc.maxTrials)) {
                            capped += 1u;
                            st.counts.w = 1u;
                            st.x1.w = pc.trialCap == TRIAL_CAP_DROP ? 0.0 : st.target.w / st.wo.w;
                            status = PSMS_DONE;
                        }
                    }
                }
            }
            if (status == PSMS_DONE || bvh_iterations >= pc.stepBudget) break;
            vec2 u = status == PSMS_FIRST
                         ? partition_initial_seed(part, rng)
                         : partition_trial_seed(part, uvec2(st.pair.w & 0xFFu, (st.pair.w >> 8u) & 0xFFu),
                                                st.pair.w >> 16u, rng);
            tr = manifold_trial_start(rc.x0, rc.ng0, ml.y, ml.n, rc.es, rc.et, ml.directional,
                                      false, rc.x0 + manifold_seed_direction(space, u));
            tr.space = space;
            tr.tiles = pc.tiles;
            tr.region = manifold_seed_tile(u, pc.tiles);
            tr.first_shape = manifold_caster_shape(caster);
#ifdef MANIFOLD_ROUGH_CASTERS
            tr.offset_stream = manifold_offset_stream(psms_offset_seed(st));
#endif
            walks += 1u;
            pending = true;
        }
        Hit hit;
        bool found = trace_closest(tr.ray_o, tr.ray_d, tr.ray_tmin, tr.ray_tmax, BVH_MASK_ALL, hit);
        rays += 1u;
        manifold_trial_advance(tr, found, hit, ms);
    }
    st.hit.w = status;
    if (status != PSMS_DONE) work_list_append(d + 1u, index);
    st.rng = rng.state;
    st.counts.x += iterations;
    st.counts.y += walks;
    psms_pixels[index] = st;
    atomicAdd(psms_iterations, iterations);
    atomicAdd(psms_walks, walks);
    atomicAdd(psms_bernoulli, bernoulli);
    atomicAdd(psms_capped, capped);
    atomicAdd(psms_solved, solutions);
    atomicAdd(psms_rays, rays);
    atomicMax(psms_max_bvh_iterations, bvh_iterations);
}
