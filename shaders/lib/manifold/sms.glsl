// One specular manifold sampling trial (Zeltner et al. 2020, Alg. 1 and Sec. 4.3; MNEE seeding
// after Hanika et al. 2015) as a state machine: a seed chain is traced, walked to the manifold by
// Newton steps with re-projection, and its last segment tested for visibility. Every ray of a
// trial comes out of manifold_trial_ray and goes back through manifold_trial_advance, so a
// kernel traces all of them at one call site (shaders/lib/README.md rule 4) and can stop between
// trials to stay under lavapipe's loop limit (rule 5). The estimators (unbiased with Bernoulli
// trials, biased, MNEE) are built from trials by the caustic passes.
#ifndef LOOM_MANIFOLD_SMS_GLSL
#define LOOM_MANIFOLD_SMS_GLSL

#include "lib/bsdf.glsl"
#include "lib/bvh.glsl"
#include "lib/lights.glsl"
#include "lib/manifold/coverage.glsl"
#include "lib/manifold/seed_space.glsl"
#include "lib/manifold/walk.glsl"
#include "lib/rng.glsl"
#include "lib/sampling.glsl"
#include "lib/shading.glsl"

// Seeds: the caster triangles with an inclusive area CDF (x = triangle, y = floatBits(cdf)),
// built by the pass from the scene's caustic_caster tags.
layout(std430) readonly buffer ManifoldCasters { uvec2 manifold_casters[]; };

struct ManifoldSettings {
    uint constraint;         // MANIFOLD_CONSTRAINT_*
    uint step_control;       // MANIFOLD_STEP_*
    uint max_iterations;     // Newton steps per walk, halvings included
    float solver_threshold;  // convergence: every |C_i| below this
    float min_segment;       // shorter chain segments fail (scene-scale dependent)
    uint max_chain;          // specular vertices a chain may have (<= MANIFOLD_MAX_VERTICES)
};

// A point on a caster, uniform by area over all casters.
vec3 manifold_sample_caster(vec3 u) {
    uint lo = 0u, hi = uint(manifold_casters.length()) - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u.z < uintBitsToFloat(manifold_casters[mid].y)) hi = mid;
        else lo = mid + 1u;
    }
    vec3 a, b, c;
    triangle_positions(manifold_casters[lo].x, a, b, c);
    return sample_triangle_point(u.xy, a, b, c);
}

// The light end of a chain: a point sampled by area on an emissive triangle (pdf per area,
// selection included), or a point or spot light (pdf = selection probability).
struct ManifoldLight {
    vec3 y;
    vec3 n;      // unit normal of an area light, 0 for point lights
    vec3 s, t;   // orthonormal basis of the area light's plane
    float pdf;
    uint light;  // index of the light (scene_light)
    bool point;
    bool directional;  // y is the unit direction towards the light
    bool valid;  // false: no light SMS can connect to (untagged, environment)
};

// The light sample of light li at u (pdf per area, or 1 for a point or directional light),
// invalid for lights SMS cannot connect to.
ManifoldLight manifold_light_sample_at(uint li, vec2 u) {
    ManifoldLight ml;
    ml.valid = false;
    ml.point = false;
    ml.directional = false;
    ml.pdf = 0.0;
    ml.y = vec3(0.0);
    ml.n = vec3(0.0);
    ml.s = vec3(0.0);
    ml.t = vec3(0.0);
    ml.light = li;
    LightGpu l = scene_light(li);
    if (!manifold_emitter_light(li)) return ml;
    if (l.type == LIGHT_TRIANGLE) {
        vec3 a, b, c;
        triangle_positions(l.index, a, b, c);
        ml.y = sample_triangle_point(u, a, b, c);
        vec3 cr = cross(b - a, c - a);
        float area = 0.5 * length(cr);
        if (!(area > 0.0)) return ml;
        ml.n = normalize(cr);
        ml.s = normalize(b - a);
        ml.t = cross(ml.n, ml.s);
        ml.pdf = 1.0 / area;
        ml.valid = true;
    } else if (l.type == LIGHT_POINT || l.type == LIGHT_SPOT) {
        ml.y = l.p0.xyz;
        ml.pdf = 1.0;
        ml.point = true;
        ml.valid = true;
    } else if (l.type == LIGHT_DIRECTIONAL) {
        ml.y = normalize(l.p0.xyz);
        ml.pdf = 1.0;
        ml.directional = true;
        ml.valid = true;
    }
#ifdef MANIFOLD_ENVIRONMENT_CHAINS
    else if (manifold_light_is_environment(li)) {
        // A sampled direction ends the chain at infinity as a directional light's does, with
        // the environment's radiance over this solid-angle pdf in place of its irradiance.
        float pdf = 1.0 / (4.0 * PI);
        if (light_is(l.type, LIGHT_CONSTANT)) ml.y = sample_uniform_sphere(u);
        else ml.y = envmap_sample(l.index, u, pdf);
        ml.pdf = pdf;
        ml.directional = true;
        ml.valid = pdf > 0.0;
    }
#endif
    return ml;
}

// A light by the scene's selection pmf, then a point on it.
ManifoldLight manifold_sample_light(vec3 u) {
    ManifoldLight ml = manifold_light_sample_at(0u, u.xy);
    ml.valid = false;
    if (light_count() == 0u) return ml;
    uint li = select_light(u.z);
    float pmf = scene_light(li).pmf;
    if (!(pmf > 0.0)) return ml;
    ml = manifold_light_sample_at(li, u.xy);
    ml.pdf *= pmf;
    return ml;
}

// A light sample from what an estimator stored of it: the point, its pdf, the area light's
// normal (0 for point and directional lights) and the light index.
ManifoldLight manifold_light_from(vec3 y, float pdf, vec3 n, uint light) {
    ManifoldLight ml;
    ml.y = y;
    ml.pdf = pdf;
    ml.n = n;
    ml.light = light;
    ml.directional =
        scene_light(light).type == LIGHT_DIRECTIONAL || manifold_light_is_environment(light);
    ml.point = dot(n, n) == 0.0 && !ml.directional;
    ml.s = vec3(0.0);
    ml.t = vec3(0.0);
    if (!ml.point && !ml.directional) {
        vec3 a, b, c;
        triangle_positions(scene_light(light).index, a, b, c);
        ml.s = normalize(b - a);
        ml.t = cross(n, ml.s);
    }
    ml.valid = true;
    return ml;
}

// The receiver end of a chain: x0 with its geometric normal on the side it is seen from (the
// walk leaves x0 there), and the plane the chain's fixed end point moves in for the
// generalized geometric term (walk.glsl): the area light's, or x0's for point and directional
// lights.
struct ManifoldReceiver {
    vec3 x0, ng0, es, et;
};

ManifoldReceiver manifold_receiver(ShadingPoint sh0, vec3 wo_world, ManifoldLight ml) {
    ManifoldReceiver r;
    r.x0 = sh0.sp.p;
    r.ng0 = dot(sh0.sp.ng, wo_world) < 0.0 ? -sh0.sp.ng : sh0.sp.ng;
    r.es = ml.s;
    r.et = ml.t;
    if (ml.point || ml.directional) {
        r.es = normalize(sh0.sp.dp_du);
        r.et = cross(sh0.sp.ng, r.es);
    }
    return r;
}

const uint TRIAL_SEED = 0u;       // tracing the seed chain
const uint TRIAL_RETRACE = 1u;    // re-tracing the chain from a proposed first vertex
const uint TRIAL_SHADOW = 2u;     // visibility of the last segment towards y
const uint TRIAL_CONVERGED = 3u;  // a valid, visible solution
const uint TRIAL_FAILED = 4u;

struct ManifoldTrial {
    ManifoldChain chain;     // the accepted chain
    ManifoldChain proposal;  // the chain being traced
    uint phase;
    bool straight;           // MNEE seed: the straight line x0 -> y, no scattering
    vec3 x0, ng0;            // the receiver point and its geometric normal
    vec3 y, ny;              // the light point (ny = 0: a point light)
    vec3 ray_o, ray_d;       // the ray to trace next, hits with t in (ray_tmin, ray_tmax]
    float ray_tmin, ray_tmax;
    uint iterations;         // Newton steps taken (halvings included)
    float beta;              // step size
    vec2 step;               // the current Newton step of the first vertex
    float error;             // max |C_i| of the chain the step was taken from
    vec3 anchor_p, anchor_s, anchor_t;  // that chain's first vertex and its tangent frame
    float endpoint_det;      // end-point Jacobian determinant of the chain (walk.glsl)
    vec3 es, et;             // the plane the end point moves in: the area light's, or x0's
#ifdef MANIFOLD_ROUGH_CASTERS
    // The stream of the rough vertices' offset normals (manifold_rough_offset): vertex i of
    // every chain of an estimate takes the same two numbers, so trials reuse the offsets.
    uvec4 offset_stream;
#endif
#ifdef MANIFOLD_TRUST_REGION
    // Sample-space partitioning (Hong et al. 2025 Sec. 4.1): the chain's first caster vertex
    // is on first_shape, and its first vertex's seed-space coordinates stay in the tiles
    // around region.
    ManifoldSeedSpace space;
    uvec2 region;
    uint tiles;
    uint first_shape;
#endif
};

bool manifold_trial_running(ManifoldTrial tr) { return tr.phase < TRIAL_CONVERGED; }

#ifdef MANIFOLD_TRUST_REGION
// Whether the accepted chain's first vertex is still inside the trust region; a walk that
// leaves it aborts (Hong et al. 2025 Sec. 4.1), for the initial sample and every trial alike.
bool manifold_trial_in_region(ManifoldTrial tr) {
    vec2 u;
    if (!manifold_seed_coords(tr.space, normalize(tr.chain.v[0].p - tr.x0), u)) return false;
    return manifold_region_contains(tr.region, manifold_seed_tile(u, tr.tiles), tr.tiles);
}
#endif

// Rays of a walk start exactly at their vertex and skip its own surface by tmin: an origin
// offset along the normal would shift every re-traced vertex by up to the offset, more than the
// solver threshold allows.
void manifold_trial_ray_from(inout ManifoldTrial tr, vec3 p, vec3 ng, vec3 d) {
    float eps = 1e-4 * max(1.0, max(abs(p.x), max(abs(p.y), abs(p.z))));
    tr.ray_o = p;
    tr.ray_d = d;
    tr.ray_tmin = eps / max(abs(dot(d, ng)), 1e-2);
    tr.ray_tmax = 1e30;
}

void manifold_trial_ray_towards(inout ManifoldTrial tr, vec3 p, vec3 ng, vec3 target) {
    manifold_trial_ray_from(tr, p, ng, normalize(target - p));
}

// Starts a trial from x0 towards seed (SMS: a point on a caster, scattered onwards) or along the
// straight line to y (straight, MNEE).
// (es, et): orthonormal basis of the light's plane (area lights) or of x0's (point and
// directional lights). directional: y is the unit direction towards the light.
ManifoldTrial manifold_trial_start(vec3 x0, vec3 ng0, vec3 y, vec3 ny, vec3 es, vec3 et,
                                   bool directional, bool straight, vec3 seed) {
    ManifoldTrial tr;
    tr.phase = TRIAL_SEED;
    tr.straight = straight;
    tr.x0 = x0;
    tr.ng0 = ng0;
    tr.y = y;
    tr.ny = ny;
    tr.iterations = 0u;
    tr.beta = 1.0;
    tr.step = vec2(0.0);
    tr.error = 0.0;
    tr.anchor_p = x0;
    tr.anchor_s = vec3(0.0);
    tr.anchor_t = vec3(0.0);
    tr.endpoint_det = 0.0;
    tr.es = es;
    tr.et = et;
    tr.chain.k = 0u;
    tr.proposal.k = 0u;
    tr.chain.end_at_infinity = directional;
    tr.proposal.end_at_infinity = directional;
#ifdef MANIFOLD_ROUGH_CASTERS
    tr.offset_stream = uvec4(0u);  // the caller sets an estimate's own before the first advance
#endif
    manifold_trial_ray_towards(tr, x0, ng0, straight ? (directional ? x0 + y : y) : seed);
    if (straight && !directional) tr.ray_tmax = length(y - x0) * (1.0 - 1e-4);
    return tr;
}

// Rough casters: the offset stream of an estimate given as two words. PartitionedSMS keeps them
// in its reservoir samples (manifold_sample_offset_seed), so that the manifold shift replays the
// same offset normals: with them held, a chain through rough vertices is specular again and the
// shift keeps the sample's primary coordinates (x_n and the offsets' random numbers), Jacobian 1.
uvec4 manifold_offset_stream(uvec2 seed) { return uvec4(seed, 0x0FF5E7A1u, 0u); }

// Where the first vertex moves for step size beta: p - beta (s dX0 + t dX1) (Zeltner Sec. 4.3),
// from the chain the step was taken at.
void manifold_trial_propose(inout ManifoldTrial tr) {
    tr.iterations += 1u;
    vec3 target = tr.anchor_p - tr.beta * (tr.anchor_s * tr.step.x + tr.anchor_t * tr.step.y);
    manifold_trial_ray_towards(tr, tr.x0, tr.ng0, target);
    tr.proposal.k = 0u;
    tr.phase = TRIAL_RETRACE;
}

// A proposal that left the shape sequence (miss, other shape, total internal reflection):
// halve the step (one of the max_iterations).
void manifold_trial_reject(inout ManifoldTrial tr, ManifoldSettings ms) {
    tr.beta *= 0.5;
    if (tr.iterations >= ms.max_iterations) tr.phase = TRIAL_FAILED;
    else manifold_trial_propose(tr);
}

// At an accepted chain: converged (then the shadow ray), or the next Newton step.
void manifold_trial_evaluate(inout ManifoldTrial tr, ManifoldSettings ms) {
    ManifoldLinearSolve ls = manifold_linear_solve(ms.constraint, tr.chain, tr.x0, tr.y,
                                                   dot(tr.ny, tr.ny) > 0.0, tr.es, tr.et);
    if (ls.error >= 0.0 && ls.error < ms.solver_threshold) {
        tr.endpoint_det = ls.endpoint_det;
        if (!ls.ok || !manifold_chain_types_valid(tr.chain, tr.x0, tr.y, ms.min_segment)) {
            tr.phase = TRIAL_FAILED;
            return;
        }
        ManifoldVertex last = tr.chain.v[tr.chain.k - 1u];
        ShadowRay r = tr.chain.end_at_infinity ? shadow_ray_infinite(last.p, last.ng, tr.y)
                                               : shadow_ray_between(last.p, last.ng, tr.y, tr.ny);
        tr.ray_o = r.o;
        tr.ray_d = r.d;
        tr.ray_tmin = 0.0;
        tr.ray_tmax = r.tmax;
        tr.phase = TRIAL_SHADOW;
        return;
    }
    if (ms.step_control == MANIFOLD_STEP_DESCENT && tr.iterations > 0u &&
        !(ls.error < tr.error)) {
        manifold_trial_reject(tr, ms);
        return;
    }
    if (!ls.ok || tr.iterations >= ms.max_iterations) {
        tr.phase = TRIAL_FAILED;
        return;
    }
    if (tr.iterations > 0u) tr.beta = min(1.0, 2.0 * tr.beta);
    tr.error = ls.error;
    tr.anchor_p = tr.chain.v[0].p;
    tr.anchor_s = tr.chain.v[0].s;
    tr.anchor_t = tr.chain.v[0].t;
    tr.step = ls.step;
    manifold_trial_propose(tr);
}

// Continues the chain being traced past its last vertex v (index i): scatter specularly.
bool manifold_trial_scatter_on(inout ManifoldTrial tr, ManifoldChain c, uint i) {
    ManifoldVertex v = c.v[i];
    vec3 prev = i == 0u ? tr.x0 : c.v[i - 1u].p;
    SpecularScatter s = manifold_scatter(v, normalize(prev - v.p));
    if (!s.valid) return false;
    manifold_trial_ray_from(tr, v.p, v.ng, s.w);
    return true;
}

// The seed chain is complete: the walk starts from it (true), or there is none (no vertex, or
// only bouncers: coverage.glsl's chains have a caster).
bool manifold_trial_begin_walk(inout ManifoldTrial tr) {
    bool caster = false;
    for (uint j = 0u; j < tr.proposal.k; ++j) {
        bool here = (scene_shape(tr.proposal.v[j].shape).flags & SHAPE_CAUSTIC_CASTER) != 0u;
#ifdef MANIFOLD_TRUST_REGION
        // A chain belongs to the pair of its first caster vertex: seeds aimed at another
        // caster that reach this chain must not count it twice.
        if (here && !caster && tr.proposal.v[j].shape != tr.first_shape) break;
#endif
        caster = caster || here;
    }
    if (!caster) {
        tr.phase = TRIAL_FAILED;
        return false;
    }
    tr.chain = tr.proposal;
    manifold_choose_frames(tr.chain, tr.y);
    return true;
}

// Feeds the result of tracing the trial's ray (found, hit) back. The walk is evaluated at one
// place (its linear solve is the largest code of a trial).
void manifold_trial_advance(inout ManifoldTrial tr, bool found, Hit hit, ManifoldSettings ms) {
    if (tr.phase == TRIAL_SHADOW) {
        tr.phase = found ? TRIAL_FAILED : TRIAL_CONVERGED;
        return;
    }
    bool evaluate = false, append = false;
    uint i = tr.proposal.k;
    bool seeding = tr.phase == TRIAL_SEED;
    if (seeding) {
        ShapeGpu shape = scene_shape(scene_triangle(found ? hit.prim : 0u).w);
        bool chain_surface =
            found && manifold_chain_surface(shape.flags, scene_material(shape.material));
        if (!chain_surface) {
            // The straight line reached y or a blocker (MNEE fails there); the scattered SMS
            // seed left the casters (its chain ends) or never reached one.
            if (found && (tr.straight || i == 0u)) tr.phase = TRIAL_FAILED;
            else evaluate = manifold_trial_begin_walk(tr);
        } else if (i >= ms.max_chain) {
            tr.phase = TRIAL_FAILED;
        } else {
            append = true;
        }
    } else if (!found || scene_triangle(hit.prim).w != tr.chain.v[i].shape) {
        // TRIAL_RETRACE: vertex i of the proposal must be on the accepted chain's shape i.
        manifold_trial_reject(tr, ms);
    } else {
        append = true;
    }
    if (append) {
        tr.proposal.v[i] = manifold_vertex(hit.prim, hit.bary);
#ifdef MANIFOLD_ROUGH_CASTERS
        Rng offset_rng = rng_from_seed(uvec4(tr.offset_stream.xyz, i));
        manifold_rough_offset(tr.proposal.v[i], rng_next2(offset_rng));
#endif
        tr.proposal.k = i + 1u;
        if (!seeding && tr.proposal.k == tr.chain.k) {
            for (uint j = 0u; j < tr.chain.k; ++j) tr.chain.v[j] = tr.proposal.v[j];
            evaluate = true;
#ifdef MANIFOLD_TRUST_REGION
            if (!manifold_trial_in_region(tr)) {
                tr.phase = TRIAL_FAILED;
                evaluate = false;
            }
#endif
        } else if (seeding && tr.straight) {
            ManifoldVertex v = tr.proposal.v[i];
            manifold_trial_ray_from(tr, v.p, v.ng, tr.ray_d);
            if (!tr.chain.end_at_infinity) tr.ray_tmax = length(tr.y - v.p) * (1.0 - 1e-4);
        } else if (!manifold_trial_scatter_on(tr, tr.proposal, i)) {
            // Total internal reflection: a seed chain ends here (the constraint's TIR swap
            // can still walk it out); a re-traced chain has left its shape sequence.
            if (seeding) evaluate = manifold_trial_begin_walk(tr);
            else manifold_trial_reject(tr, ms);
        }
    }
    if (evaluate) manifold_trial_evaluate(tr, ms);
}

// Direction of a solution's first segment, which identifies it (Zeltner Sec. 4.3: two trials
// found the same solution when these agree to the uniqueness threshold).
vec3 manifold_trial_direction(ManifoldTrial tr) { return normalize(tr.chain.v[0].p - tr.x0); }

bool manifold_same_solution(vec3 a, vec3 b, float uniqueness_threshold) {
    return abs(dot(a, b) - 1.0) < uniqueness_threshold;
}

// The contribution f T Le G / pdf of a converged trial at the receiver sh0 (outgoing direction
// wo in its local frame), without the estimator's weight (K, 1). geometric_clamp > 0 clamps
// the generalized geometric term (biased; the reference code clamps it for directional
// lights and the single-scatter determinant at 1).
vec3 manifold_trial_contribution(ManifoldTrial tr, ManifoldSettings ms, ShadingPoint sh0,
                                 vec3 wo, ManifoldLight ml, float geometric_clamp) {
    ManifoldChain c = tr.chain;
    vec3 wi = normalize(c.v[0].p - tr.x0);
    vec3 wi_local = shading_to_local(sh0, wi);
    vec3 f = bsdf_eval(sh0.mat, wo, wi_local);
    if (!any(greaterThan(f, vec3(0.0)))) return vec3(0.0);
    float radiance_scale, etendue_scale;
    vec3 T = manifold_chain_throughput(c, tr.x0, tr.y, radiance_scale, etendue_scale);
#ifdef MANIFOLD_ROUGH_CASTERS
    T *= manifold_chain_rough_weight(c, tr.x0, tr.y);
#endif
    ManifoldVertex last = c.v[c.k - 1u];
    vec3 L;
    float G;
    if (ml.point || ml.directional) {
        // Irradiance I d omega_y / dA_x0 (point) or E |cos_k| |det| (directional), carried
        // as flux (T without the radiance scaling), times the BSDF without its cosine.
        vec3 E;
        if (ml.point) {
            vec3 w;
            float dist;
            E = point_light_incident(scene_light(ml.light), last.p, w, dist) * dist * dist;
        } else if (manifold_light_is_environment(ml.light)) {
            E = environment_radiance(tr.y);  // over ml.pdf below: per solid angle
        } else {
            E = scene_light(ml.light).p1.rgb;
        }
        L = E / (max(abs(wi_local.z), 1e-8) * radiance_scale * etendue_scale);
        G = manifold_geometric_term(c, tr.x0, tr.y, false, tr.endpoint_det);
    } else {
        L = emitted_radiance(scene_triangle(scene_light(ml.light).index).w, ml.n,
                             normalize(tr.y - last.p));
        G = manifold_geometric_term(c, tr.x0, tr.y, true, tr.endpoint_det);
    }
    if (geometric_clamp > 0.0) G = min(G, geometric_clamp);
    vec3 v = f * T * L * (G / ml.pdf);
    return any(isnan(v)) || any(isinf(v)) ? vec3(0.0) : v;
}

#endif
