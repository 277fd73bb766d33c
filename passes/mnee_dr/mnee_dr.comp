#version 460
// MNEEDimReduction: the reference path tracer without the paths a single specular vertex
// covers (manifold/coverage.glsl), plus, at a caustic receiver (seen directly or through
// purely specular surfaces), manifold next-event
// estimation with dimension reduction (Granizo-Hidalgo & Holzschuch 2024): one light sample,
// the coplanarity walk (manifold/coplanar_walk.glsl), and Eq. 25's contribution
// I_e F A rho / D. One solution per receiver point (biased: a second solution is missed).
#include "lib/camera.glsl"
#include "lib/integrator/path.glsl"
#include "lib/manifold/coplanar_walk.glsl"
#include "lib/manifold/sms.glsl"
#include "lib/rng.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint maxTriangles;
    uint maxBisections;
    float bisectionTolerance;
    uint bothDirections;
    uint maxBounces;
    uint rrDepth;
    uint misHeuristic;
    uint excludeCovered;
    uint receiverDepth;
} pc;

layout(rgba32f) uniform writeonly image2D colorImage;
#if HAS_CAUSTIC
layout(rgba32f) uniform writeonly image2D causticImage;
#endif
#if HAS_STATS
layout(rgba32f) uniform writeonly image2D statsImage;
#endif
// Frame totals, mirrored by MNEEDimReductionPass.cpp: walks, one count per COPLANAR_* status,
// triangles entered, bisection steps, the largest BVH step count of an invocation, rays.
layout(std430) buffer MneeDrCounters { uint mnee_dr_counters[16]; };
const uint COUNTER_WALKS = 0u, COUNTER_STATUS = 1u, COUNTER_TRIANGLES = 9u,
           COUNTER_BISECTIONS = 10u, COUNTER_MAX_STEPS = 11u, COUNTER_RAYS = 12u;

struct MneeDrEstimate {
    vec3 value;
    vec4 stats;  // triangles crossed, bisection steps, solution found (and visible), walk run
    uint rays;
};

// One estimate at the receiver sh seen from wo_world, towards the light sample ml.
MneeDrEstimate mnee_dr_estimate(ShadingPoint sh, vec3 wo_world, ManifoldLight ml) {
    MneeDrEstimate e;
    e.value = vec3(0.0);
    CoplanarSettings cs;
    cs.max_triangles = pc.maxTriangles;
    cs.max_bisections = pc.maxBisections;
    cs.bisection_tolerance = pc.bisectionTolerance;
    cs.both_directions = pc.bothDirections != 0u;
    vec3 ngP = dot(sh.sp.ng, wo_world) < 0.0 ? -sh.sp.ng : sh.sp.ng;
    // The walk starts on the side of the receiver's surface it is seen from.
    vec3 P = offset_ray_origin(sh.sp.p, ngP, ngP);
    CoplanarQuery q = coplanar_query(P, ml.y, ml.directional);
    CoplanarResult res = coplanar_walk(q, cs);
    e.rays = 1u;
    uint status = res.status;
    if (status == COPLANAR_SOLVED) {
        ManifoldVertex v = manifold_vertex(res.prim, res.bary);
        ShadowRay a = shadow_ray_between(sh.sp.p, ngP, v.p, v.ng);
        ShadowRay b = ml.directional ? shadow_ray_infinite(v.p, v.ng, ml.y)
                                     : shadow_ray_between(v.p, v.ng, ml.y, ml.n);
        e.rays += 2u;
        if (trace_any(a.o, a.d, 0.0, a.tmax, BVH_MASK_ALL) ||
            trace_any(b.o, b.d, 0.0, b.tmax, BVH_MASK_ALL))
            status = COPLANAR_OCCLUDED;
    }
    if (status == COPLANAR_SOLVED) {
        // Eq. 25: the light's intensity towards M (area light: L_e |cos| / pdf_A; directional:
        // irradiance), the flux transmittance (1 - F) (A = 1: clear media), the receiver's BSDF
        // with its cosine, over the focusing factor D.
        ManifoldChain c;
        c.k = 1u;
        c.end_at_infinity = ml.directional;
        c.v[0] = manifold_vertex(res.prim, res.bary);
        float radiance_scale;
        vec3 T = manifold_chain_throughput(c, sh.sp.p, radiance_scale);
        vec3 wi_local = shading_to_local(sh, normalize(res.M - sh.sp.p));
        vec3 f = bsdf_eval(sh.mat, shading_to_local(sh, wo_world), wi_local);
        vec3 I;
        if (ml.directional) {
            I = scene_lights[ml.light].p1.rgb;
        } else if (ml.point) {
            vec3 w;
            float dist;
            I = point_light_incident(scene_lights[ml.light], res.M, w, dist) * dist * dist;
        } else {
            vec3 wl = normalize(res.M - ml.y);
            I = emitted_radiance(scene_triangles[scene_lights[ml.light].index].w, ml.n, -wl) *
                abs(dot(ml.n, wl));
        }
        CoplanarTriangle tri = coplanar_triangle(res.prim, q);
        float D = coplanar_focusing(tri, res.bary, q);
        e.value = f * T * I / (radiance_scale * D * ml.pdf);
        if (!(D > 0.0) || any(isnan(e.value)) || any(isinf(e.value))) e.value = vec3(0.0);
    }
    atomicAdd(mnee_dr_counters[COUNTER_WALKS], 1u);
    atomicAdd(mnee_dr_counters[COUNTER_STATUS + status], 1u);
    atomicAdd(mnee_dr_counters[COUNTER_TRIANGLES], res.triangles);
    atomicAdd(mnee_dr_counters[COUNTER_BISECTIONS], res.bisections);
    e.stats = vec4(float(res.triangles), float(res.bisections),
                   status == COPLANAR_SOLVED ? 1.0 : 0.0, 1.0);
    return e;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    // The path tracer's stream and sample order (PathTracer with one sample per frame).
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed);
    vec2 uv = (vec2(pixel) + rng_next2(rng)) / vec2(pc.frameSize);
    vec2 u_lens = rng_next2(rng);
    CameraFrame cam = camera_frame(scene_info.camera_open, scene_info.camera_close, 0.0);
    vec3 o, d;
    camera_ray(cam, uv, u_lens, o, d);

    PathSettings ps;
    ps.max_bounces = pc.maxBounces;
    ps.rr_depth = pc.rrDepth;
    ps.mis_heuristic = pc.misHeuristic;
    ps.nee = true;
    ps.mis = true;
    ps.covered_max_chain = pc.excludeCovered != 0u ? 1u : 0u;
    ps.covered_depth = pc.receiverDepth;
    Hit none;
    none.t = 0.0;
    none.prim = ~0u;
    none.bary = vec2(0.0);
    PathRadiance pr = path_trace(o, d, false, none, false, ps, rng);
    uint rays = pr.rays;

    vec3 caustic = vec3(0.0);
    vec4 stats = vec4(0.0);
    // The receiver: the camera path's first vertex with a smooth lobe, seen through at most
    // receiverDepth purely specular vertices (a pool floor under water), as the path tracer's
    // coverage defines it. The specular prefix is sampled on a stream of its own, as is the
    // light (SpecularManifoldSampling's), so that the path part is the path tracer's image.
    Rng srng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x5A17C0DEu);
    vec3 u_light = vec3(rng_next2(srng), rng_next(srng));
    Hit h = pr.first;
    bool found = pr.found;
    vec3 dir = d, beta = vec3(1.0);
    for (uint depth = 0u; found; ++depth) {
        ShadingPoint sh = shading_point(h);
        if ((bsdf_flags(sh.mat) & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u) {
            if (manifold_receiver(sh.shape_flags, sh.mat)) {
                ManifoldLight ml = manifold_sample_light(u_light);
                if (ml.valid) {
                    MneeDrEstimate e = mnee_dr_estimate(sh, -dir, ml);
                    caustic = beta * e.value;
                    rays += e.rays;
                    stats = e.stats;
                }
            }
            break;
        }
        if (depth >= pc.receiverDepth) break;
        BsdfSample bs = bsdf_sample(sh.mat, shading_to_local(sh, -dir),
                                    vec3(rng_next(srng), rng_next2(srng)));
        if (!bsdf_sample_valid(bs)) break;
        beta *= bsdf_sample_weight(bs);
        dir = shading_to_world(sh, bs.wi);
        found = trace_closest(offset_ray_origin(sh.sp.p, sh.sp.ng, dir), dir, 0.0, 1e30,
                              BVH_MASK_ALL, h);
        rays += 1u;
    }
    imageStore(colorImage, ivec2(pixel), vec4(pr.L + caustic, 1.0));
#if HAS_CAUSTIC
    imageStore(causticImage, ivec2(pixel), vec4(caustic, 1.0));
#endif
#if HAS_STATS
    imageStore(statsImage, ivec2(pixel), stats);
#endif
    atomicAdd(mnee_dr_counters[COUNTER_RAYS], rays);
    atomicMax(mnee_dr_counters[COUNTER_MAX_STEPS], bvh_iterations);
}
