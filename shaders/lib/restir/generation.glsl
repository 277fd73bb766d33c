// ReSTIR PT candidate generation (Lin et al. 2022, Sec. 5): one path tree from the primary hit,
// every NEE sample and every emitter hit a candidate, resampled by streaming RIS. Paths are the
// ones PathTracer samples (same NEE + BSDF MIS, integrator/nee.glsl; same maximum length;
// Russian roulette only after the reconnection vertex, where shifts never replay), so the mean
// of a ReSTIR estimator equals the reference path tracer's. Each candidate stores what
// hybrid_shift.glsl needs to rebuild it at another pixel (PathSample, reservoir.glsl).
#ifndef LOOM_RESTIR_GENERATION_GLSL
#define LOOM_RESTIR_GENERATION_GLSL

#include "lib/color.glsl"
#include "lib/integrator/nee.glsl"
#include "lib/manifold/coverage.glsl"
#include "lib/restir/path_rules.glsl"
#include "lib/restir/primary.glsl"
#include "lib/restir/reservoir.glsl"
#include "lib/scene.glsl"

// Candidate generation: trace one path from the primary hit, streaming every NEE sample and every
// emitter hit into r with resampling weight luminance(contribution) * inv_candidates (RIS with
// target luminance(F); the contribution is F / p in the mixed measure).

struct GenState {
    uint k;           // reconnection index found so far (0 = none)
    uint kind;
    uint rc_id;
    vec2 rc_bary;
    vec3 rc_dir;      // omega_k once sampled
    float p_mixed;    // density of x_k (area) times the suffix sampling pdfs so far
    float p_rc;       // the factors of p_mixed that depend on x_{k-1}: x_k's density and,
                      // once sampled, that of x_k's successor (restir_reconnection_pdf)
    vec3 suffix_f;    // product of f at x_{k+1} .. x_{j-1}
};

// The reconnection part of a candidate's sample.
void path_sample_set_rc(inout PathSample s, uint flags, uint rc_id, vec2 rc_bary, vec3 rc_dir,
                        vec3 rc_Lo) {
    s.flags = flags;
    s.rc_id = rc_id;
    s.rc_bary = rc_bary;
    s.rc_dir = rc_dir;
    s.rc_Lo = rc_Lo;
}

// C = F / p_mixed (the integrand over the sampling density); rr_weight = 1 / (Russian roulette
// survival probabilities): part of the source density, never of F.
// p_rc: the factors of p_mixed that a shift to another pixel changes (GenState.p_rc; 1 without
// a reconnection vertex).
//
// A kernel that does something else with the candidates than RIS defines
// RESTIR_CANDIDATE_CALLBACK before including this file and its own restir_candidate() with this
// signature (G-PT, passes/gradient_domain/gpt.comp, shifts each one to the neighbouring pixels).
#ifdef RESTIR_CANDIDATE_CALLBACK
void restir_candidate(inout PathReservoir r, inout Rng rng_sel, PathSample s, vec3 C,
                      float p_mixed, float p_rc, float inv_candidates, float rr_weight);
#else
void restir_candidate(inout PathReservoir r, inout Rng rng_sel, PathSample s, vec3 C,
                      float p_mixed, float p_rc, float inv_candidates, float rr_weight) {
    float w = luminance(C) * inv_candidates * rr_weight;
    vec3 F = C * p_mixed;
    reservoir_add(r, s, F, luminance(F), w, rng_next(rng_sel));
}
#endif

// Returns the number of rays traced. Russian roulette from vertex rr_depth on, only once the
// reconnection vertex x_k is behind: the suffix after x_k is never replayed (shifts keep its
// directions and cached radiance), so a termination decision there is a sampling choice of
// this pixel only; the prefix that shifts replay never depends on throughput.
uint restir_generate(RestirSettings cfg, PrimaryHit ph, uvec4 seed, vec4 film_lens, float time,
                     float inv_candidates, uint rr_depth, inout PathReservoir r, inout Rng rng_sel) {
    uint rays = 0u;
    if (!primary_valid(ph) || cfg.max_bounces == 0u) return rays;
    ShadingPoint sh = restir_primary_shading(ph);
    vec3 d = normalize(sh.sp.p - ph.camera.xyz);
    vec3 beta = vec3(1.0);
    float rr_weight = 1.0;
    GenState g;
    g.k = 0u;
    g.kind = RC_SURFACE;
    g.rc_id = 0u;
    g.rc_bary = vec2(0.0);
    g.rc_dir = vec3(0.0);
    g.p_mixed = 1.0;
    g.p_rc = 1.0;
    g.suffix_f = vec3(1.0);
    PathSample s;
    s.seed = seed;
    s.time = time;
    s.film_lens = film_lens;
    // Paths a caustic estimator covers are no candidates (cfg.covered_max_chain > 0).
    ManifoldCoverage cov = manifold_coverage_none();
    for (uint j = 1u; j <= cfg.max_bounces; ++j) {
        bool rough_j = restir_vertex_rough(sh.mat, cfg.rough_threshold);
        vec3 wo = shading_to_local(sh, -d);
        uint flags = bsdf_flags(sh.mat);
        vec3 u_light, u_bsdf;
        restir_vertex_randoms(seed, j, u_light, u_bsdf);

        // NEE candidate: the path x1 .. xj, light (n = j + 1).
        if ((flags & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u) {
            NeeSample nee = nee_sample(sh, wo, u_light, true, cfg.mis_heuristic);
            LightSample ls = nee.ls;
            if (nee.valid) {
                vec3 f = nee.f;
                float w = nee.mis;
                ++rays;
                if (!trace_any(nee.ray.o, nee.ray.d, 0.0, nee.ray.tmax, BVH_MASK_ALL)) {
                    vec3 C = beta * nee.value;
                    LightGpu l = scene_light(ls.light);
                    uint kind = l.type == LIGHT_TRIANGLE ? RC_SURFACE
                              : (l.type == LIGHT_POINT || l.type == LIGHT_SPOT) ? RC_POINT : RC_DIRECTION;
                    s.light_pdf = ls.pdf;
                    float p_mixed, p_rc;
                    if (g.k != 0u) {
                        // k == n-1: the last MIS weight is re-evaluated by the shift.
                        bool last = g.k == j;
                        path_sample_set_rc(s, path_pack_flags(j + 1u, g.k, true, g.kind, ls.is_delta),
                                           g.rc_id, g.rc_bary, last ? ls.wi : g.rc_dir,
                                           last ? ls.Li : g.suffix_f * f * ls.Li * w);
                        p_mixed = g.p_mixed * ls.pdf;
                        p_rc = last ? g.p_rc * ls.pdf : g.p_rc;
                    } else if (restir_reconnectable(cfg, j + 1u, rough_j, true, ls.dist)) {
                        // The light vertex itself is the reconnection vertex.
                        bool tri = kind == RC_SURFACE;
                        path_sample_set_rc(s, path_pack_flags(j + 1u, j + 1u, true, kind, ls.is_delta),
                                           tri ? l.index : ls.light,
                                           tri ? triangle_barycentrics(l.index, sh.sp.p + ls.wi * ls.dist)
                                               : vec2(0.0),
                                           ls.wi, vec3(0.0));
                        p_mixed = ls.pdf;
                        if (kind == RC_SURFACE) {
                            vec3 a, b, c;
                            triangle_positions(l.index, a, b, c);
                            float cos_l = abs(dot(normalize(cross(b - a, c - a)), ls.wi));
                            p_mixed *= cos_l / (ls.dist * ls.dist);
                        }
                        p_rc = p_mixed;
                    } else {
                        path_sample_set_rc(s, path_pack_flags(j + 1u, 0u, true, RC_SURFACE, ls.is_delta),
                                           0u, vec2(0.0), vec3(0.0), vec3(0.0));
                        p_mixed = 1.0;
                        p_rc = 1.0;
                    }
                    restir_candidate(r, rng_sel, s, C, p_mixed, p_rc, inv_candidates, rr_weight);
                }
            }
        }

        // BSDF sampling towards x_{j+1}.
        BsdfSample bs = bsdf_sample(sh.mat, wo, u_bsdf);
        if (!bsdf_sample_valid(bs)) break;
        cov = manifold_coverage_step(cov, sh, cfg.covered_depth, cfg.covered_max_chain, bs.flags);
        bool delta = (bs.flags & BSDF_DELTA) != 0u;
        vec3 beta_next = beta * bsdf_sample_weight(bs);
        if (g.k != 0u && j >= rr_depth) {
            // Survival probability on the throughput, as PathTracer's Russian roulette.
            vec3 b = beta_next * rr_weight;
            float q = min(max(b.r, max(b.g, b.b)), 0.95);
            if (rng_next(rng_sel) >= q) break;
            rr_weight /= q;
        }
        vec3 dn = shading_to_world(sh, bs.wi);
        vec3 o = offset_ray_origin(sh.sp.p, sh.sp.ng, dn);
        Hit hit;
        ++rays;
        bool found = trace_closest(o, dn, 0.0, 1e30, BVH_MASK_ALL, hit);
        ShadingPoint sn;
        float dist = 1e30, cos_next = 1.0;
        if (found) {
            sn = shading_point(hit);
            dist = length(sn.sp.p - o);
            cos_next = abs(dot(sn.sp.ng, dn));
        }
        vec3 Le = emitter_hit_radiance(dn, found, sn);
        // Emitter-hit candidate: the path x1 .. x_{j+1} (n = j + 1).
        if (any(greaterThan(Le, vec3(0.0))) &&
            !(found && manifold_coverage_covers(cov, sn.shape_flags))) {
            float light_pdf = emitter_hit_light_pdf(sh.sp.p, dn, found, hit.prim, sn);
            float w = delta ? 1.0 : mis_weight(bs.pdf, light_pdf, cfg.mis_heuristic);
            vec3 C = beta_next * Le * w;
            s.light_pdf = light_pdf;
            float p_mixed, p_rc;
            if (g.k != 0u) {
                bool last = g.k == j;
                path_sample_set_rc(s, path_pack_flags(j + 1u, g.k, false, g.kind, false), g.rc_id,
                                   g.rc_bary, last ? dn : g.rc_dir,
                                   last ? Le : g.suffix_f * bs.f * Le * w);
                p_mixed = g.p_mixed * bs.pdf;
                p_rc = last ? g.p_rc * bs.pdf : g.p_rc;
            } else if (!delta && restir_reconnectable(cfg, j + 1u, rough_j, true, dist)) {
                uint kind = found ? RC_SURFACE : RC_DIRECTION;
                path_sample_set_rc(s, path_pack_flags(j + 1u, j + 1u, false, kind, false),
                                   found ? hit.prim : scene_info.counts.w,
                                   found ? hit.bary : vec2(0.0), dn, vec3(0.0));
                p_mixed = bs.pdf * (found ? cos_next / (dist * dist) : 1.0);
                p_rc = p_mixed;
            } else {
                path_sample_set_rc(s, path_pack_flags(j + 1u, 0u, false, RC_SURFACE, false), 0u,
                                   vec2(0.0), vec3(0.0), vec3(0.0));
                p_mixed = 1.0;
                p_rc = 1.0;
            }
            restir_candidate(r, rng_sel, s, C, p_mixed, p_rc, inv_candidates, rr_weight);
        }
        if (!found || j == cfg.max_bounces) break;

        // Advance the reconnection bookkeeping to x_{j+1}.
        if (g.k != 0u) {
            if (g.k == j) {
                g.rc_dir = dn;
                g.p_rc *= bs.pdf;
            } else {
                g.suffix_f *= bs.f;
            }
            g.p_mixed *= bs.pdf;
        } else if (!delta && restir_reconnectable(cfg, j + 1u, rough_j,
                                                  restir_vertex_rough(sn.mat, cfg.rough_threshold), dist)) {
            g.k = j + 1u;
            g.kind = RC_SURFACE;
            g.rc_id = hit.prim;
            g.rc_bary = hit.bary;
            g.p_mixed = bs.pdf * cos_next / (dist * dist);
            g.p_rc = g.p_mixed;
        }
        beta = beta_next;
        d = dn;
        sh = sn;
        if (all(equal(beta, vec3(0.0)))) break;
    }
    return rays;
}

#endif
