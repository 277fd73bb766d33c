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
    uint covered_depth;      // ...from receivers behind at most this many specular vertices
                             // (0: seen directly; coverage.glsl)
};

struct PathRadiance {
    vec3 L;         // radiance along the path
    vec3 L_direct;  // emission seen directly + one-bounce lighting
    vec3 albedo;    // first-hit reflectance and shading normal (0 on a miss)
    vec3 normal;
    uint rays;      // closest-hit and shadow rays traced
    bool found;     // the camera ray hit a surface
    Hit first;      // that hit
    // The path's receivers (manifold/coverage.glsl, at most MANIFOLD_MAX_RECEIVERS): where a
    // caustic estimator adds what the path leaves out, with the throughput and direction the
    // path arrived with.
    uint receivers;
    Hit receiver_hit[MANIFOLD_MAX_RECEIVERS];
    vec3 receiver_beta[MANIFOLD_MAX_RECEIVERS];  // throughput up to it (Russian roulette included)
    vec3 receiver_wo[MANIFOLD_MAX_RECEIVERS];    // unit direction from it back along the path
};

// What a path carries from one vertex to the next: the ray to trace, the throughput and what
// MIS and SMS coverage need of the vertex before. Schedules differ only in where this lives:
// registers for path_trace's loop, a buffer between the dispatches of PathTracer's wavefront.
struct PathVertexState {
    vec3 o, d;        // the ray to trace next
    vec3 beta;        // throughput
    float prev_pdf;   // solid-angle pdf of the BSDF sample that led here
    bool prev_delta;  // that sample was delta (camera rays count as delta: no MIS at the first hit)
    vec3 prev_p;
    ManifoldCoverage cov;
    uint depth;       // scattering events so far
};

// A light sample taken at a vertex: what it adds if its shadow ray is unoccluded.
struct PendingShadow {
    ShadowRay ray;
    vec3 c;
    bool direct;  // taken at the primary hit: also one-bounce lighting
    bool valid;   // false: nothing to trace
};

PathVertexState path_start(vec3 o, vec3 d) {
    PathVertexState st;
    st.o = o;
    st.d = d;
    st.beta = vec3(1.0);
    st.prev_pdf = 0.0;
    st.prev_delta = true;
    st.prev_p = o;
    st.cov = manifold_coverage_none();
    st.depth = 0u;
    return st;
}

PathRadiance path_radiance_none() {
    PathRadiance r;
    r.L = vec3(0.0);
    r.L_direct = vec3(0.0);
    r.albedo = vec3(0.0);
    r.normal = vec3(0.0);
    r.rays = 0u;
    r.found = false;
    r.first.t = 0.0;
    r.first.prim = ~0u;
    r.first.bary = vec2(0.0);
    r.receivers = 0u;
    for (uint i = 0u; i < uint(MANIFOLD_MAX_RECEIVERS); ++i) {
        r.receiver_hit[i] = r.first;
        r.receiver_beta[i] = vec3(0.0);
        r.receiver_wo[i] = vec3(0.0);
    }
    return r;
}

// The vertex that the ray (st.o, st.d) found (found: hit, else the environment): emission,
// MIS-weighted against light sampling; a light sample (returned in `shadow`, for the caller to
// trace and add with path_add_shadow); a BSDF sample that sets up the next ray; Russian
// roulette. Returns false when the path ends here (its light sample may still be pending).
// Random numbers: 3 for light sampling, 3 for the BSDF, 1 for Russian roulette, in that order.
bool path_vertex(inout PathVertexState st, inout PathRadiance r, bool found, Hit hit,
                 PathSettings ps, inout Rng rng, out PendingShadow shadow) {
    shadow.valid = false;
    shadow.direct = st.depth == 0u;
    shadow.c = vec3(0.0);
    shadow.ray.o = vec3(0.0);
    shadow.ray.d = vec3(0.0);
    shadow.ray.tmax = 0.0;
    if (st.depth == 0u) {
        r.found = found;
        r.first = hit;
    }
    ShadingPoint sh;
    if (found) sh = shading_point(hit);
    // Emission hit by BSDF sampling (or seen directly), or the environment on a miss,
    // MIS-weighted against light sampling.
    vec3 Le = emitter_hit_radiance(st.d, found, sh);
    if (any(greaterThan(Le, vec3(0.0))) &&
        !(found ? manifold_coverage_covers(st.cov, sh.shape_flags)
                : manifold_coverage_covers_miss(st.cov))) {
        float w = 1.0;
        if (!st.prev_delta && ps.mis)
            w = mis_weight(st.prev_pdf,
                           emitter_hit_light_pdf(st.prev_p, st.d, found, hit.prim, sh),
                           ps.mis_heuristic);
        else if (!st.prev_delta && ps.nee)
            w = 0.0;
        vec3 c = st.beta * Le * w;
        r.L += c;
        if (st.depth <= 1u) r.L_direct += c;
    }
    if (!found) return false;
    if (st.depth == 0u) {
        r.albedo = sh.mat.diffuse.rgb;
        r.normal = sh.n;
    }
    if (st.depth >= ps.max_bounces) return false;

    vec3 wo = shading_to_local(sh, -st.d);
    uint flags = bsdf_flags(sh.mat);
    bool has_smooth = (flags & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u;
    if (manifold_coverage_receiver(st.cov, sh, ps.covered_depth) &&
        r.receivers < uint(MANIFOLD_MAX_RECEIVERS)) {
        r.receiver_hit[r.receivers] = hit;
        r.receiver_beta[r.receivers] = st.beta;
        r.receiver_wo[r.receivers] = -st.d;
        ++r.receivers;
    }

    // Next-event estimation.
    vec3 u_light = vec3(rng_next2(rng), rng_next(rng));
    if (has_smooth && ps.nee) {
        NeeSample nee = nee_sample(sh, wo, u_light, ps.mis, ps.mis_heuristic);
#ifdef MANIFOLD_ROUGH_CASTERS
        if (nee.valid && manifold_coverage_covers_light_sample(
                             st.cov, sh, ps.covered_depth, ps.covered_max_chain, wo,
                             shading_to_local(sh, nee.ls.wi), nee.ls.light))
            nee.valid = false;
#endif
        if (nee.valid) {
            shadow.ray = nee.ray;
            shadow.c = st.beta * nee.value;
            shadow.valid = true;
        }
    }

    // BSDF sampling.
    vec3 u_bsdf = vec3(rng_next(rng), rng_next2(rng));
    BsdfSample bs = bsdf_sample(sh.mat, wo, u_bsdf);
    if (!bsdf_sample_valid(bs)) return false;
    st.cov = manifold_coverage_step(st.cov, sh, ps.covered_depth, ps.covered_max_chain, bs.flags);
    st.beta *= bsdf_sample_weight(bs);
    st.prev_delta = (bs.flags & BSDF_DELTA) != 0u;
    st.prev_pdf = bs.pdf;
    st.prev_p = sh.sp.p;
    st.d = shading_to_world(sh, bs.wi);
    st.o = offset_ray_origin(sh.sp.p, sh.sp.ng, st.d);

    // Russian roulette on the throughput (unbiased: survivors are reweighted).
    if (st.depth + 1u >= ps.rr_depth) {
        float q = min(max(st.beta.r, max(st.beta.g, st.beta.b)), 0.95);
        if (rng_next(rng) >= q) return false;
        st.beta /= q;
    }
    if (all(equal(st.beta, vec3(0.0)))) return false;
    ++st.depth;
    return true;
}

// A light sample whose shadow ray was unoccluded.
void path_add_shadow(inout PathRadiance r, PendingShadow shadow) {
    r.L += shadow.c;
    if (shadow.direct) r.L_direct += shadow.c;
}

// The path from ray (o, d), all of it in this invocation. With `given`, the first hit is
// first_hit (found: first_found) instead of a trace (a GBuffer's V-buffer).
PathRadiance path_trace(vec3 o, vec3 d, bool given, Hit first_hit, bool first_found,
                        PathSettings ps, inout Rng rng) {
    PathRadiance r = path_radiance_none();
    PathVertexState st = path_start(o, d);
    for (;;) {
        Hit hit;
        bool found;
        if (given && st.depth == 0u) {
            hit = first_hit;
            found = first_found;
        } else {
            ++r.rays;
            found = trace_closest(st.o, st.d, 0.0, 1e30, BVH_MASK_ALL, hit);
        }
        PendingShadow shadow;
        bool more = path_vertex(st, r, found, hit, ps, rng, shadow);
        if (shadow.valid) {
            ++r.rays;
            if (!trace_any(shadow.ray.o, shadow.ray.d, 0.0, shadow.ray.tmax, BVH_MASK_ALL))
                path_add_shadow(r, shadow);
        }
        if (!more) break;
    }
    return r;
}

#endif
