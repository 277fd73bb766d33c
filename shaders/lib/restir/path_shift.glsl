// ReSTIR PT paths (Lin et al. 2022, Sec. 5-6): candidate generation along one path tree (every
// NEE sample and every emitter hit is a candidate, resampled by streaming RIS), and the shift
// of a stored path to another pixel's primary hit by random replay, reconnection or the hybrid
// of both. Paths are the ones PathTracer samples (same NEE + BSDF MIS, same maximum length;
// Russian roulette only after the reconnection vertex, where shifts never replay), so the mean
// of a ReSTIR estimator equals the reference path tracer's.
//
// Reconnection vertex (hybrid shift, Lin et al. Sec. 6.2): the first x_k, k >= 2, such that
// x_{k-1} and x_k are both rough (no delta lobe, alpha > rough_threshold; the last vertex of a
// path counts as rough) and |x_k - x_{k-1}| >= dist_threshold. The offset path must pick the
// same k (no earlier pair qualifies, y_{k-1} rough, segment long enough), else the shift is not
// a bijection and is rejected.
//
// Measure: primary sample space for the replayed prefix (Jacobian 1), area at x_k (a fixed
// point: Jacobian 1) and solid angle after it (directions fixed: Jacobian 1). The solid-angle
// form of the same shift, reconnection_jacobian below times the prefix pdf ratio, is what one
// multiplies by when storing the integrand in path space instead.
#ifndef LOOM_RESTIR_PATH_SHIFT_GLSL
#define LOOM_RESTIR_PATH_SHIFT_GLSL

#include "lib/color.glsl"
#include "lib/integrator/nee.glsl"
#include "lib/restir/path_reservoir.glsl"

// Shift statistics (attempts / successes by kind), read back by the passes for Lua/inspector.
layout(std430) buffer RestirCounters {
    uint shift_attempts_reconnect;
    uint shift_success_reconnect;
    uint shift_attempts_replay;
    uint shift_success_replay;
    uint shift_rays;  // rays traced by shifts (and by the domain changes of path_reuse.glsl)
    uint shift_max_bvh_iterations;  // most traversal steps of one invocation (bvh.glsl limit)
};

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

// Vertex classification for the reconnection criteria: diffuse, or linear roughness sqrt(alpha)
// above the threshold (the roughness Lin et al.'s Falcor code compares with 0.2, alpha > 0.04).
// Materials with a delta lobe (smooth coatings, glass) never count, whichever lobe was sampled.
bool restir_vertex_rough(Material m, float threshold) {
    uint flags = bsdf_flags(m);
    if ((flags & BSDF_DELTA) != 0u || (flags & (BSDF_DIFFUSE | BSDF_GLOSSY)) == 0u) return false;
    return material_type(m) == MATERIAL_DIFFUSE || sqrt(material_alpha(m)) > threshold;
}

// Is (x_{k-1}, x_k) a reconnection pair under the settings' shift?
bool restir_reconnectable(RestirSettings cfg, uint k, bool rough_prev, bool rough_k, float dist) {
    if (cfg.shift == SHIFT_REPLAY) return false;
    if (cfg.shift == SHIFT_RECONNECTION) return k == 2u && rough_prev && rough_k;
    return rough_prev && rough_k && dist >= cfg.dist_threshold;
}

// The random numbers of vertex x_j: counters 4j+1 .. 4j+4 of the replay stream, the same for
// the path's generation and every replay of it.
void restir_vertex_randoms(uvec4 seed, uint j, out vec3 u_light, out vec3 u_bsdf) {
    Rng r = rng_from_seed(seed);
    r.state.w = 4u * j;
    u_light = vec3(rng_next2(r), rng_next(r));
    u_bsdf = vec3(rng_next(r), rng_next2(r));
}

// The primary hit of the camera ray through film position (pixel + film_lens.xy) with lens
// sample film_lens.zw, seen by camera `pose` (Area ReSTIR samples carry these; the ray is traced
// again in every domain). A miss keeps the ray direction.
PrimaryHit restir_trace_primary(CameraPose pose, ivec2 pixel, vec4 film_lens, uvec2 frame_size) {
    CameraFrame cam = camera_frame(pose, pose, 0.0);
    vec3 o, d;
    camera_ray(cam, (vec2(pixel) + film_lens.xy) / vec2(frame_size), film_lens.zw, o, d);
    PrimaryHit ph;
    ph.camera = vec4(o, 1.0);
    Hit hit;
    ph.hit = trace_closest(o, d, 0.0, 1e30, BVH_MASK_ALL, hit)
                 ? uvec4(hit.prim, floatBitsToUint(hit.bary), 0u)
                 : uvec4(~0u, floatBitsToUint(d));
    return ph;
}

ShadingPoint restir_primary_shading(PrimaryHit ph) {
    Hit h;
    h.t = 0.0;
    h.prim = ph.hit.x;
    h.bary = uintBitsToFloat(ph.hit.yz);
    return shading_point(h);
}

vec2 triangle_barycentrics(uint prim, vec3 p) {
    vec3 a, b, c;
    triangle_positions(prim, a, b, c);
    vec3 e1 = b - a, e2 = c - a, v = p - a;
    float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    float dv1 = dot(v, e1), dv2 = dot(v, e2);
    float det = d11 * d22 - d12 * d12;
    if (det == 0.0) return vec2(1.0 / 3.0);
    return vec2(d22 * dv1 - d12 * dv2, d11 * dv2 - d12 * dv1) / det;
}

// ---------------------------------------------------------------------------------------------
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
void restir_stream_candidate(inout PathReservoir r, inout Rng rng_sel, PathSample s, vec3 C,
                             float p_mixed, float inv_candidates, float rr_weight) {
    float w = luminance(C) * inv_candidates * rr_weight;
    vec3 F = C * p_mixed;
    reservoir_add(r, s, F, luminance(F), w, rng_next(rng_sel));
}

// Returns the number of rays traced. Russian roulette from vertex rr_depth on, only once the
// reconnection vertex x_k is behind: the suffix after x_k is never replayed (shifts keep its
// directions and cached radiance), so a termination decision there is a sampling choice of
// this pixel only; the prefix that shifts replay never depends on throughput.
uint restir_generate(RestirSettings cfg, PrimaryHit ph, uvec4 seed, vec4 film_lens,
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
    g.suffix_f = vec3(1.0);
    PathSample s;
    s.seed = seed;
    s.pad = 0.0;
    s.film_lens = film_lens;
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
                    LightGpu l = scene_lights[ls.light];
                    uint kind = l.type == LIGHT_TRIANGLE ? RC_SURFACE
                              : (l.type == LIGHT_POINT || l.type == LIGHT_SPOT) ? RC_POINT : RC_DIRECTION;
                    s.light_pdf = ls.pdf;
                    float p_mixed;
                    if (g.k != 0u) {
                        // k == n-1: the last MIS weight is re-evaluated by the shift.
                        bool last = g.k == j;
                        path_sample_set_rc(s, path_pack_flags(j + 1u, g.k, true, g.kind, ls.is_delta),
                                           g.rc_id, g.rc_bary, last ? ls.wi : g.rc_dir,
                                           last ? ls.Li : g.suffix_f * f * ls.Li * w);
                        p_mixed = g.p_mixed * ls.pdf;
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
                    } else {
                        path_sample_set_rc(s, path_pack_flags(j + 1u, 0u, true, RC_SURFACE, ls.is_delta),
                                           0u, vec2(0.0), vec3(0.0), vec3(0.0));
                        p_mixed = 1.0;
                    }
                    restir_stream_candidate(r, rng_sel, s, C, p_mixed, inv_candidates, rr_weight);
                }
            }
        }

        // BSDF sampling towards x_{j+1}.
        BsdfSample bs = bsdf_sample(sh.mat, wo, u_bsdf);
        if (!bsdf_sample_valid(bs)) break;
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
        vec3 Le = vec3(0.0);
        float light_pdf = 0.0;
        float dist = 1e30, cos_next = 1.0;
        if (found) {
            sn = shading_point(hit);
            dist = length(sn.sp.p - o);
            cos_next = abs(dot(sn.sp.ng, dn));
            if (any(greaterThan(sn.emission, vec3(0.0)))) {
                Le = emitted_radiance(sn.sp.shape, sn.sp.ng, dn);
                light_pdf = light_pdf_triangle(sh.sp.p, hit.prim, sn.sp.p, sn.sp.ng);
            }
        } else {
            Le = environment_radiance(dn);
            light_pdf = light_pdf_environment(dn);
        }
        // Emitter-hit candidate: the path x1 .. x_{j+1} (n = j + 1).
        if (any(greaterThan(Le, vec3(0.0)))) {
            float w = delta ? 1.0 : mis_weight(bs.pdf, light_pdf, cfg.mis_heuristic);
            vec3 C = beta_next * Le * w;
            s.light_pdf = light_pdf;
            float p_mixed;
            if (g.k != 0u) {
                bool last = g.k == j;
                path_sample_set_rc(s, path_pack_flags(j + 1u, g.k, false, g.kind, false), g.rc_id,
                                   g.rc_bary, last ? dn : g.rc_dir,
                                   last ? Le : g.suffix_f * bs.f * Le * w);
                p_mixed = g.p_mixed * bs.pdf;
            } else if (!delta && restir_reconnectable(cfg, j + 1u, rough_j, true, dist)) {
                uint kind = found ? RC_SURFACE : RC_DIRECTION;
                path_sample_set_rc(s, path_pack_flags(j + 1u, j + 1u, false, kind, false),
                                   found ? hit.prim : scene_info.counts.w,
                                   found ? hit.bary : vec2(0.0), dn, vec3(0.0));
                p_mixed = bs.pdf * (found ? cos_next / (dist * dist) : 1.0);
            } else {
                path_sample_set_rc(s, path_pack_flags(j + 1u, 0u, false, RC_SURFACE, false), 0u,
                                   vec2(0.0), vec3(0.0), vec3(0.0));
                p_mixed = 1.0;
            }
            restir_stream_candidate(r, rng_sel, s, C, p_mixed, inv_candidates, rr_weight);
        }
        if (!found || j == cfg.max_bounces) break;

        // Advance the reconnection bookkeeping to x_{j+1}.
        if (g.k != 0u) {
            if (g.k == j) g.rc_dir = dn;
            else g.suffix_f *= bs.f;
            g.p_mixed *= bs.pdf;
        } else if (!delta && restir_reconnectable(cfg, j + 1u, rough_j,
                                                  restir_vertex_rough(sn.mat, cfg.rough_threshold), dist)) {
            g.k = j + 1u;
            g.kind = RC_SURFACE;
            g.rc_id = hit.prim;
            g.rc_bary = hit.bary;
            g.p_mixed = bs.pdf * cos_next / (dist * dist);
        }
        beta = beta_next;
        d = dn;
        sh = sn;
        if (all(equal(beta, vec3(0.0)))) break;
    }
    return rays;
}

// ---------------------------------------------------------------------------------------------
// Shift: the integrand of sample s at another pixel's primary hit dst (0 when the shift fails).

// MIS weight of the path's last vertex given the pdfs at its predecessor.
float restir_last_mis(RestirSettings cfg, PathSample s, float light_pdf, float bsdf_pdf_) {
    if (path_last_delta_light(s)) return 1.0;
    return path_last_nee(s) ? mis_weight(light_pdf, bsdf_pdf_, cfg.mis_heuristic)
                            : mis_weight(bsdf_pdf_, light_pdf, cfg.mis_heuristic);
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
};

bool restir_reconnect_begin(RestirSettings cfg, PathSample s, ShadingPoint sy, vec3 d,
                            out Reconnection rc, out ShadowRay ray) {
    uint n = path_length(s), k = path_rc_index(s);
    vec3 wo = shading_to_local(sy, -d);
    uint kind = path_rc_kind(s);
    float dist;
    rc.light_pdf = 0.0;
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
        LightGpu l = scene_lights[s.rc_id];
        if (l.type == LIGHT_DIRECTIONAL) {
            rc.G_Le = l.p1.rgb;
        } else {
            rc.G_Le = environment_radiance(rc.dir);
            rc.light_pdf = light_pdf_environment(rc.dir);
        }
        ray = shadow_ray_infinite(sy.sp.p, sy.sp.ng, rc.dir);
    } else {
        LightGpu l = scene_lights[s.rc_id];
        rc.G_Le = point_light_incident(l, sy.sp.p, rc.dir, dist);
        if (!(dist >= cfg.dist_threshold) && cfg.shift == SHIFT_HYBRID) return false;
        ray = shadow_ray_between(sy.sp.p, sy.sp.ng, l.p0.xyz, vec3(0.0));
    }
    vec3 wi = shading_to_local(sy, rc.dir);
    rc.f = bsdf_eval(sy.mat, wo, wi);
    if (all(equal(rc.f, vec3(0.0))) || all(equal(rc.G_Le, vec3(0.0)))) return false;
    rc.bsdf_pdf = k == n ? bsdf_pdf(sy.mat, wo, wi) : 0.0;
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

// Every ray of a shift goes through the one traversal in the loop below (lavapipe compiles each
// inlined BVH traversal separately: code size is speed).
vec3 restir_shift(RestirSettings cfg, PathSample s, PrimaryHit dst) {
    uint n = path_length(s), k = path_rc_index(s);
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
        if (step == SHIFT_STEP_LAST_BSDF) {
            vec3 Le;
            float light_pdf, dist = 1e30;
            if (found) {
                ShadingPoint sn = shading_point(hit);
                dist = length(sn.sp.p - ray_o);
                Le = any(greaterThan(sn.emission, vec3(0.0)))
                         ? emitted_radiance(sn.sp.shape, sn.sp.ng, ray_d) : vec3(0.0);
                light_pdf = light_pdf_triangle(sh.sp.p, hit.prim, sn.sp.p, sn.sp.ng);
            } else {
                Le = environment_radiance(ray_d);
                light_pdf = light_pdf_environment(ray_d);
            }
            if (!delta && restir_reconnectable(cfg, n, rough_j, true, dist)) break;
            float w = delta ? 1.0 : mis_weight(bs.pdf, light_pdf, cfg.mis_heuristic);
            result = beta * bsdf_sample_weight(bs) * Le * w;
            break;
        }
        if (!found) break;
        ShadingPoint sn = shading_point(hit);
        // The offset path must not find an earlier reconnection vertex than the base path.
        if (!delta && restir_reconnectable(cfg, j + 1u, rough_j,
                                           restir_vertex_rough(sn.mat, cfg.rough_threshold),
                                           length(sn.sp.p - ray_o)))
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

#endif
