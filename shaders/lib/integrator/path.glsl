// One camera path of the reference path tracer: BSDF sampling and next-event estimation
// combined by MIS (Veach 1997), Russian roulette, optionally without the paths specular
// manifold sampling produces (manifold/coverage.glsl) when an SMS estimator adds them instead.
// PathTracer and the caustic passes run their paths through this one function.
#ifndef LOOM_INTEGRATOR_PATH_GLSL
#define LOOM_INTEGRATOR_PATH_GLSL

#include "lib/bsdf.glsl"
#include "lib/bvh.glsl"
#include "lib/integrator/nee.glsl"
#include "lib/manifold/coverage.glsl"
#include "lib/rng.glsl"
#include "lib/shading.glsl"

struct PathSettings {
    uint max_bounces;      // scattering events; 1 = direct lighting only
    uint rr_depth;         // Russian roulette after this many bounces
    uint mis_heuristic;    // MIS_HEURISTIC_*
    bool nee;              // light sampling at non-delta vertices
    bool mis;              // weigh NEE against BSDF-sampled emitter hits (else hits count 0
                           // when nee, 1 without it)
    uint covered_max_chain;  // > 0: drop the paths SMS covers, chains up to this length...
    uint covered_depth;      // ...from the first vertex with a smooth lobe, a receiver at
                             // most this deep (0: the primary hit; coverage.glsl)
};

struct PathRadiance {
    vec3 L;         // radiance along the path
    vec3 L_direct;  // emission seen directly + one-bounce lighting
    vec3 albedo;    // first-hit reflectance and shading normal (0 on a miss)
    vec3 normal;
    uint rays;      // closest-hit and shadow rays traced
    bool found;     // the camera ray hit a surface
    Hit first;      // that hit
};

// The path from ray (o, d). With `given`, the first hit is first_hit (found: first_found)
// instead of a trace (a GBuffer's V-buffer). Random numbers: per bounce, 3 for light sampling,
// 3 for the BSDF, 1 for Russian roulette, in that order.
PathRadiance path_trace(vec3 o, vec3 d, bool given, Hit first_hit, bool first_found,
                        PathSettings ps, inout Rng rng) {
    PathRadiance r;
    r.L = vec3(0.0);
    r.L_direct = vec3(0.0);
    r.albedo = vec3(0.0);
    r.normal = vec3(0.0);
    r.rays = 0u;
    r.found = false;
    vec3 beta = vec3(1.0);
    float prev_pdf = 0.0;     // solid-angle pdf of the BSDF sample that led here
    bool prev_delta = true;   // camera rays count as delta (no MIS at the first hit)
    vec3 prev_p = o;
    ManifoldCoverage cov = manifold_coverage_none();
    for (uint depth = 0u;; ++depth) {
        Hit hit;
        bool found;
        if (given && depth == 0u) {
            hit = first_hit;
            found = first_found;
        } else {
            ++r.rays;
            found = trace_closest(o, d, 0.0, 1e30, BVH_MASK_ALL, hit);
        }
        if (depth == 0u) {
            r.found = found;
            r.first = hit;
        }
        ShadingPoint sh;
        if (found) sh = shading_point(hit);
        // Emission hit by BSDF sampling (or seen directly), or the environment on a miss,
        // MIS-weighted against light sampling.
        vec3 Le = emitter_hit_radiance(d, found, sh);
        if (any(greaterThan(Le, vec3(0.0))) &&
            !(found && manifold_coverage_covers(cov, sh.shape_flags))) {
            float w = 1.0;
            if (!prev_delta && ps.mis)
                w = mis_weight(prev_pdf, emitter_hit_light_pdf(prev_p, d, found, hit.prim, sh),
                               ps.mis_heuristic);
            else if (!prev_delta && ps.nee)
                w = 0.0;
            vec3 c = beta * Le * w;
            r.L += c;
            if (depth <= 1u) r.L_direct += c;
        }
        if (!found) break;
        if (depth == 0u) {
            r.albedo = sh.mat.diffuse.rgb;
            r.normal = sh.n;
        }
        if (depth >= ps.max_bounces) break;

        vec3 wo = shading_to_local(sh, -d);
        uint flags = bsdf_flags(sh.mat);
        bool has_smooth = (flags & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u;

        // Next-event estimation.
        vec3 u_light = vec3(rng_next2(rng), rng_next(rng));
        if (has_smooth && ps.nee) {
            NeeSample nee = nee_sample(sh, wo, u_light, ps.mis, ps.mis_heuristic);
            if (nee.valid) {
                ++r.rays;
                if (!trace_any(nee.ray.o, nee.ray.d, 0.0, nee.ray.tmax, BVH_MASK_ALL)) {
                    vec3 c = beta * nee.value;
                    r.L += c;
                    if (depth == 0u) r.L_direct += c;
                }
            }
        }

        // BSDF sampling.
        vec3 u_bsdf = vec3(rng_next(rng), rng_next2(rng));
        BsdfSample bs = bsdf_sample(sh.mat, wo, u_bsdf);
        if (!bsdf_sample_valid(bs)) break;
        cov = manifold_coverage_step(cov, sh, depth, ps.covered_depth, ps.covered_max_chain,
                                     bs.flags);
        beta *= bsdf_sample_weight(bs);
        prev_delta = (bs.flags & BSDF_DELTA) != 0u;
        prev_pdf = bs.pdf;
        prev_p = sh.sp.p;
        d = shading_to_world(sh, bs.wi);
        o = offset_ray_origin(sh.sp.p, sh.sp.ng, d);

        // Russian roulette on the throughput (unbiased: survivors are reweighted).
        if (depth + 1u >= ps.rr_depth) {
            float q = min(max(beta.r, max(beta.g, beta.b)), 0.95);
            if (rng_next(rng) >= q) break;
            beta /= q;
        }
        if (all(equal(beta, vec3(0.0)))) break;
    }
    return r;
}

#endif
