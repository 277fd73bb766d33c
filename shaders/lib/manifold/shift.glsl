// The manifold shift of Hong et al. 2025 Sec. 5: a caustic sample moves to another receiver by
// keeping its light point x_n (light-local coordinates) and solving the specular constraints
// again from the new receiver, the Newton walk seeded at the source solution and limited to a
// few iterations; it must keep the source's shape sequence. It is made a bijection by walking
// back: the same solve from the source receiver, seeded at the shifted solution, must find the
// source solution again (otherwise the shift fails). The sample's domain is x_n (area measure
// on the light) and which solution, so the shift's Jacobian is 1 for the delta BSDFs every
// chain vertex has (walk.glsl, manifold_material_specular). Rough casters (glossy; under
// MANIFOLD_ROUGH_CASTERS): a rough vertex scatters about an offset normal drawn from two random
// numbers of the sample's offset stream; the shift replays that stream, so the domain gains the
// offsets' random numbers (uniform, density 1), the shift keeps them as it keeps x_n, and its
// Jacobian is still 1 (F carries the rough vertex's weight, the integrand in those numbers).
#ifndef LOOM_MANIFOLD_SHIFT_GLSL
#define LOOM_MANIFOLD_SHIFT_GLSL

#include "lib/manifold/reservoir.glsl"
#include "lib/restir/primary.glsl"

struct ManifoldShiftSettings {
    ManifoldSettings ms;         // max_iterations: the shift's Newton budget (paper: 5)
    float uniqueness_threshold;  // the walk back found the source solution: |d.d' - 1| < this
    float geometric_clamp;       // 0 = off
    bool bijective;              // walk back (off: an ablation, biased)
};

// Shift counters of a reuse kernel (ManifoldReuseCounters in the passes' kernels).
uint manifold_shift_rays = 0u;
uint manifold_shift_back_failed = 0u;  // the solve succeeded, the walk back did not

bool manifold_receiver_valid(PrimaryHit ph) {
    if (!primary_valid(ph)) return false;
    ShadingPoint sh = restir_primary_shading(ph);
    return manifold_receiver(sh.shape_flags, sh.mat);
}

// One solve in the geometry selected now: from receiver ph towards sample s's light point,
// seeded at `seed`; the solution keeps s's light and shape sequence. F: f T Le G (no pdf).
bool manifold_solve_sample(PrimaryHit ph, ManifoldSample s, vec3 seed, ManifoldShiftSettings ss,
                           out ManifoldSample t, out vec3 F) {
    t = s;
    F = vec3(0.0);
    ShadingPoint sh = restir_primary_shading(ph);
    vec3 wo_world = normalize(ph.camera.xyz - sh.sp.p);
    ManifoldLight ml = manifold_sample_light_end(s);
    ManifoldReceiver rc = manifold_receiver(sh, wo_world, ml);
    ManifoldTrial tr = manifold_trial_start(rc.x0, rc.ng0, ml.y, ml.n, rc.es, rc.et,
                                            ml.directional, false, seed);
#if defined(MANIFOLD_ROUGH_CASTERS) && !defined(LOOM_TEST_SHIFT_OFFSETS_NOT_REPLAYED)
    tr.offset_stream = manifold_offset_stream(manifold_sample_offset_seed(s));  // replayed
#endif
    while (manifold_trial_running(tr)) {
        Hit hit;
        bool found = trace_closest(tr.ray_o, tr.ray_d, tr.ray_tmin, tr.ray_tmax, BVH_MASK_ALL, hit);
        manifold_shift_rays += 1u;
        manifold_trial_advance(tr, found, hit, ss.ms);
    }
    if (tr.phase != TRIAL_CONVERGED || tr.chain.k != manifold_sample_length(s)) return false;
    for (uint j = 0u; j < tr.chain.k; ++j)
        if (tr.chain.v[j].shape != s.shapes[j]) return false;
    t.x1.xyz = tr.chain.v[0].p;
    F = manifold_trial_contribution(tr, ss.ms, sh, shading_to_local(sh, wo_world), ml,
                                    ss.geometric_clamp);
    return luminance(F) > 0.0;
}

// T: sample s of receiver `from` (in the previous frame's geometry when from_previous) to
// receiver `to`; t and F (f T Le G at `to`) when it succeeds. One solve call site for both
// directions (lavapipe compiles every inlined walk separately).
bool manifold_shift(ManifoldSample s, PrimaryHit from, bool from_previous, PrimaryHit to,
                    bool to_previous, ManifoldShiftSettings ss, out ManifoldSample t, out vec3 F) {
    t = s;
    F = vec3(0.0);
    bool ok = true;
    ManifoldSample cur = s;
    for (uint leg = 0u; ok && leg < (ss.bijective ? 2u : 1u); ++leg) {
        bool back = leg == 1u;
        scene_select_frame(back ? from_previous : to_previous);
        ManifoldSample r;
        vec3 Fr;
        ok = manifold_solve_sample(back ? from : to, cur, cur.x1.xyz, ss, r, Fr);
        if (!ok) {
            if (back) manifold_shift_back_failed += 1u;
        } else if (!back) {
            t = r;
            F = Fr;
            cur = r;
        } else {
            vec3 x0 = surface_point(from.hit.x, uintBitsToFloat(from.hit.yz)).p;
            ok = manifold_same_solution(normalize(r.x1.xyz - x0), normalize(s.x1.xyz - x0),
                                        ss.uniqueness_threshold);
            if (!ok) manifold_shift_back_failed += 1u;
        }
    }
    scene_select_frame(false);
    if (!ok) F = vec3(0.0);
    return ok;
}

#endif
