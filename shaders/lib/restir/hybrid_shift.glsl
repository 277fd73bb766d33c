// ReSTIR PT shift of a stored path (PathSample, reservoir.glsl) to another pixel's primary hit
// (Lin et al. 2022, Sec. 6) by random replay, reconnection or the hybrid of both, and the
// Jacobians of reconnection. The reconnection vertex rules are path_rules.glsl's, shared with
// generation.glsl.
//
// Measure: primary sample space for the replayed prefix (Jacobian 1), area at x_k (a fixed
// point: Jacobian 1) and solid angle after it (directions fixed: Jacobian 1). The solid-angle
// form of the same shift, reconnection_jacobian below times the prefix pdf ratio, is what one
// multiplies by when storing the integrand in path space instead.
#ifndef LOOM_RESTIR_HYBRID_SHIFT_GLSL
#define LOOM_RESTIR_HYBRID_SHIFT_GLSL

#include "lib/integrator/nee.glsl"
#include "lib/manifold/coverage.glsl"
#include "lib/restir/counters.glsl"
#include "lib/restir/path_rules.glsl"
#include "lib/restir/primary.glsl"
#include "lib/restir/reservoir.glsl"

// Solid-angle Jacobian of reconnecting to x_k from a new predecessor (Lin et al. Eq. 17;
// Kettunen et al. 2015): |d omega_y / d omega_x| = (cos_y / d_y^2) * (d_x^2 / cos_x), where
// cos_* is the angle at x_k between its normal and the segment to the old (x) / new (y) vertex.
float reconnection_jacobian(vec3 x_prev, vec3 y_prev, vec3 x_k, vec3 n_k) {
    vec3 dx = x_prev - x_k, dy = y_prev - x_k;
    float dx2 = dot(dx, dx), dy2 = dot(dy, dy);
    float cos_x = abs(dot(n_k, dx)) * inversesqrt(dx2);
    float cos_y = abs(dot(n_k, dy)) * inversesqrt(dy2);
    return cos_x > 0.0 ? (cos_y / dy2) * (dx2 / cos_x) : 0.0;
}

// Primary-sample-space form: the reconnection direction's random numbers change with the
// sampling pdfs at the new and old predecessor (and at x_k when the path continues past it).
float reconnection_jacobian_pss(float J_solid, float pdf_y_prev, float pdf_x_prev, float pdf_y_k,
                                float pdf_x_k) {
    float den = pdf_x_prev * pdf_x_k;
    return den > 0.0 ? J_solid * (pdf_y_prev * pdf_y_k) / den : 0.0;
}

// Shift: the integrand of sample s at another pixel's primary hit dst (0 when the shift fails).

// MIS weight of the path's last vertex given the pdfs at its predecessor.
float restir_last_mis(RestirSettings cfg, PathSample s, float light_pdf, float bsdf_pdf_) {
    return mis_weight_last_vertex(path_last_nee(s), path_last_delta_light(s), light_pdf, bsdf_pdf_,
                                  cfg.mis_heuristic);
}

// Reconnection of y (the offset path's x_{k-1}, shading point sy, incoming direction d) to the
// stored x_k, split around its visibility ray: begin evaluates everything that needs no ray
// (false: the shift fails without one), end finishes once y -> x_k is known to be unoccluded.
struct Reconnection {
    ShadingPoint sk;  // x_k (surface kind)
    vec3 dir;         // y -> x_k
    vec3 f;           // BSDF at y
    vec3 G_Le;        // k == n: what the light contributes to the segment (Le * G or I / d^2)
    float light_pdf;
    float bsdf_pdf;   // at y towards x_k
    float p_rc;       // restir_reconnection_pdf: x_k's density from y and its successor's
    float G;          // |cos at x_k| / d^2 of the segment y -> x_k (surface kind), else 1
};

// The factors of the offset path's density (GenState.p_rc's, mixed measure) that depend on its
// predecessor y of x_k: the density of x_k (area; solid angle for a light direction) and, when
// the path continues past x_k, that of x_k's successor. The rest of the suffix is the base
// path's. G-PT's MIS weights between a pixel's paths and its neighbours' shifted ones need it.
float restir_reconnection_pdf(PathSample s, ShadingPoint sy, vec3 wo, vec3 wi, Reconnection rc,
                              float dist) {
    uint n = path_length(s), k = path_rc_index(s), kind = path_rc_kind(s);
    float G = kind == RC_SURFACE ? abs(dot(rc.sk.sp.ng, rc.dir)) / (dist * dist) : 1.0;
    if (k == n) {
        // Light sampling's density of a point or direction light does not depend on y.
        if (path_last_nee(s)) return kind == RC_SURFACE ? rc.light_pdf * G : s.light_pdf;
        return bsdf_pdf(sy.mat, wo, wi) * G;
    }
    float p = bsdf_pdf(sy.mat, wo, wi) * G;
    if (k + 1u == n && path_last_nee(s)) return p * s.light_pdf;
    return p * bsdf_pdf(rc.sk.mat, shading_to_local(rc.sk, -rc.dir), shading_to_local(rc.sk, s.rc_dir));
}

bool restir_reconnect_begin(RestirSettings cfg, PathSample s, ShadingPoint sy, vec3 d,
                            out Reconnection rc, out ShadowRay ray) {
    uint n = path_length(s), k = path_rc_index(s);
    vec3 wo = shading_to_local(sy, -d);
    uint kind = path_rc_kind(s);
    float dist;
    rc.light_pdf = 0.0;
    rc.G = 1.0;
    if (kind == RC_SURFACE) {
        Hit h;
        h.t = 0.0;
        h.prim = s.rc_id;
        h.bary = s.rc_bary;
        rc.sk = shading_point(h);
        // Same segment geometry as the sampler: BSDF rays leave from the offset origin, light
        // samples from the surface point itself.
        vec3 o = sy.sp.p;
        if (!(k == n && path_last_nee(s)))
            o = offset_ray_origin(sy.sp.p, sy.sp.ng, normalize(rc.sk.sp.p - sy.sp.p));
        vec3 v = rc.sk.sp.p - o;
        dist = length(v);
        rc.dir = v / dist;
        if (!(dist >= cfg.dist_threshold) && cfg.shift == SHIFT_HYBRID) return false;
        float G = abs(dot(rc.sk.sp.ng, rc.dir)) / (dist * dist);
        rc.G = G;
        if (k == n) {
            rc.G_Le = emitted_radiance(rc.sk.sp.shape, rc.sk.sp.ng, rc.dir) * G;
            rc.light_pdf = light_pdf_triangle(sy.sp.p, s.rc_id, rc.sk.sp.p, rc.sk.sp.ng);
        } else {
            rc.G_Le = vec3(G);
        }
        ray = shadow_ray_between(sy.sp.p, sy.sp.ng, rc.sk.sp.p, rc.sk.sp.ng);
    } else if (kind == RC_DIRECTION) {
        rc.dir = s.rc_dir;
        dist = 1e30;
        LightGpu l = scene_light(s.rc_id);
        if (l.type == LIGHT_DIRECTIONAL) {
            rc.G_Le = l.p1.rgb;
        } else {
            rc.G_Le = environment_radiance(rc.dir);
            rc.light_pdf = light_pdf_environment(rc.dir);
        }
        ray = shadow_ray_infinite(sy.sp.p, sy.sp.ng, rc.dir);
    } else {
        LightGpu l = scene_light(s.rc_id);
        rc.G_Le = point_light_incident(l, sy.sp.p, rc.dir, dist);
        if (!(dist >= cfg.dist_threshold) && cfg.shift == SHIFT_HYBRID) return false;
        ray = shadow_ray_between(sy.sp.p, sy.sp.ng, l.p0.xyz, vec3(0.0));
    }
    vec3 wi = shading_to_local(sy, rc.dir);
    rc.f = bsdf_eval(sy.mat, wo, wi);
    if (all(equal(rc.f, vec3(0.0))) || all(equal(rc.G_Le, vec3(0.0)))) return false;
    rc.bsdf_pdf = k == n ? bsdf_pdf(sy.mat, wo, wi) : 0.0;
    rc.p_rc = restir_reconnection_pdf(s, sy, wo, wi, rc, dist);
    return true;
}

// beta = prefix throughput (f/p) up to y.
vec3 restir_reconnect_end(RestirSettings cfg, PathSample s, Reconnection rc, vec3 beta) {
    uint n = path_length(s), k = path_rc_index(s);
    if (k == n) return beta * rc.f * rc.G_Le * restir_last_mis(cfg, s, rc.light_pdf, rc.bsdf_pdf);
    // x_k scatters towards the stored direction; re-evaluate its BSDF (and the last MIS weight
    // when the next vertex is the last one) for the new incoming direction.
    vec3 wo_k = shading_to_local(rc.sk, -rc.dir);
    vec3 wi_k = shading_to_local(rc.sk, s.rc_dir);
    vec3 f_k = bsdf_eval(rc.sk.mat, wo_k, wi_k);
    float w = k + 1u == n ? restir_last_mis(cfg, s, s.light_pdf, bsdf_pdf(rc.sk.mat, wo_k, wi_k)) : 1.0;
    return beta * rc.f * rc.G_Le * f_k * s.rc_Lo * w;
}

// Steps of a shift; each traces exactly one ray.
const uint SHIFT_STEP_PREFIX = 0u;     // replay x_j's BSDF sample towards y_{j+1}
const uint SHIFT_STEP_RECONNECT = 1u;  // visibility y_{k-1} -> x_k
const uint SHIFT_STEP_LAST_NEE = 2u;   // pure replay: the last vertex is x_{n-1}'s NEE sample
const uint SHIFT_STEP_LAST_BSDF = 3u;  // pure replay: the last vertex is its BSDF sample

// What a shift knows about the offset path's reconnection besides its integrand.
struct ShiftDensity {
    float p_rc;  // restir_reconnection_pdf (1 for pure random replay, whose densities in primary
                 // sample space are the base path's)
    float G_rc;  // Reconnection.G: the area-to-solid-angle factor at x_k (1 without a surface x_k)
};

// Every ray of a shift goes through the one traversal in the loop below (lavapipe compiles each
// inlined BVH traversal separately: code size is speed).
vec3 restir_shift_with_density(RestirSettings cfg, PathSample s, PrimaryHit dst, out ShiftDensity sd) {
    uint n = path_length(s), k = path_rc_index(s);
    sd.p_rc = 1.0;
    sd.G_rc = 1.0;
    if (n < 2u || !primary_valid(dst)) return vec3(0.0);
    bool reconnect = k != 0u;
    if (reconnect) atomicAdd(shift_attempts_reconnect, 1u);
    else atomicAdd(shift_attempts_replay, 1u);
    if (!reconnect && cfg.shift == SHIFT_RECONNECTION) return vec3(0.0);
    ShadingPoint sh = restir_primary_shading(dst);
    vec3 d = normalize(sh.sp.p - dst.camera.xyz);
    vec3 beta = vec3(1.0);
    uint last_replayed = reconnect ? k - 1u : n - 1u;
    vec3 result = vec3(0.0);
    uint rays = 0u;
    // A replayed path that a caustic estimator covers is outside this integrand (generation.glsl
    // leaves such paths out). Only pure replay can meet one: a covered path has no smooth vertex
    // after its receiver, hence no reconnection vertex.
    ManifoldCoverage cov = manifold_coverage_none();
    for (uint j = 1u;; ++j) {
        bool rough_j = restir_vertex_rough(sh.mat, cfg.rough_threshold);
        vec3 wo = shading_to_local(sh, -d);
        uint step = j < last_replayed ? SHIFT_STEP_PREFIX
                  : reconnect         ? SHIFT_STEP_RECONNECT
                  : path_last_nee(s)  ? SHIFT_STEP_LAST_NEE
                                      : SHIFT_STEP_LAST_BSDF;
        vec3 u_light, u_bsdf;
        restir_vertex_randoms(s.seed, j, u_light, u_bsdf);
        vec3 ray_o, ray_d;
        float ray_tmax = 1e30;
        Reconnection rc;
        NeeSample nee;
        BsdfSample bs;
        ShadowRay shadow;
        if (step == SHIFT_STEP_RECONNECT) {
            if (!restir_reconnectable(cfg, k, rough_j, true, 1e30)) break;
            if (!restir_reconnect_begin(cfg, s, sh, d, rc, shadow)) break;
            sd.p_rc = rc.p_rc;
            sd.G_rc = rc.G;
        } else if (step == SHIFT_STEP_LAST_NEE) {
            if ((bsdf_flags(sh.mat) & (BSDF_DIFFUSE | BSDF_GLOSSY)) == 0u) break;
            nee = nee_sample(sh, wo, u_light, true, cfg.mis_heuristic);
            if (!nee.valid) break;
            if (restir_reconnectable(cfg, n, rough_j, true, nee.ls.dist)) break;  // not invertible
            shadow = nee.ray;
        } else {
            // Replay the BSDF sample of x_j towards y_{j+1}.
            bs = bsdf_sample(sh.mat, wo, u_bsdf);
            if (!bsdf_sample_valid(bs)) break;
            cov = manifold_coverage_step(cov, sh, cfg.covered_depth, cfg.covered_max_chain,
                                         bs.flags);
            ray_d = shading_to_world(sh, bs.wi);
            ray_o = offset_ray_origin(sh.sp.p, sh.sp.ng, ray_d);
        }
        bool any_hit = step == SHIFT_STEP_RECONNECT || step == SHIFT_STEP_LAST_NEE;
        if (any_hit) {
            ray_o = shadow.o;
            ray_d = shadow.d;
            ray_tmax = shadow.tmax;
        }
        ++rays;
        Hit hit;
        bool found = bvh_traverse(ray_o, ray_d, 0.0, ray_tmax, BVH_MASK_ALL, any_hit, hit);
        if (any_hit) {
            if (found) break;  // occluded
            if (step == SHIFT_STEP_RECONNECT) {
                result = restir_reconnect_end(cfg, s, rc, beta);
            } else {
                result = beta * nee.value;
            }
            break;
        }
        bool delta = (bs.flags & BSDF_DELTA) != 0u;
        // What the replayed BSDF sample found: the last vertex, or the next one of the prefix.
        ShadingPoint sn;
        float dist = 1e30;
        if (found) {
            sn = shading_point(hit);
            dist = length(sn.sp.p - ray_o);
        }
        if (step == SHIFT_STEP_LAST_BSDF) {
            if (found && manifold_coverage_covers(cov, sn.shape_flags)) break;
            vec3 Le = emitter_hit_radiance(ray_d, found, sn);
            if (!delta && restir_reconnectable(cfg, n, rough_j, true, dist)) break;
            float light_pdf = emitter_hit_light_pdf(sh.sp.p, ray_d, found, hit.prim, sn);
            float w = delta ? 1.0 : mis_weight(bs.pdf, light_pdf, cfg.mis_heuristic);
            result = beta * bsdf_sample_weight(bs) * Le * w;
            break;
        }
        if (!found) break;
        // The offset path must not find an earlier reconnection vertex than the base path.
        if (!delta && restir_reconnectable(cfg, j + 1u, rough_j,
                                           restir_vertex_rough(sn.mat, cfg.rough_threshold), dist))
            break;
        beta *= bsdf_sample_weight(bs);
        d = ray_d;
        sh = sn;
    }
    atomicAdd(shift_rays, rays);
    atomicMax(shift_max_bvh_iterations, bvh_iterations);
    bool ok = any(greaterThan(result, vec3(0.0))) && !any(isnan(result)) && !any(isinf(result));
    if (ok) {
        if (reconnect) atomicAdd(shift_success_reconnect, 1u);
        else atomicAdd(shift_success_replay, 1u);
    }
    return ok ? result : vec3(0.0);
}

vec3 restir_shift(RestirSettings cfg, PathSample s, PrimaryHit dst) {
    ShiftDensity sd;
    return restir_shift_with_density(cfg, s, dst, sd);
}

#endif
