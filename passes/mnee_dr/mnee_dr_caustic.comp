#version 460
// MNEEDimReduction, stage 2: at the camera path's receiver (its first vertex with a smooth
// lobe, seen through at most receiverDepth purely specular vertices), manifold next-event
// estimation with dimension reduction (Granizo-Hidalgo & Holzschuch 2024): one light sample,
// the coplanarity walk (manifold/coplanar_walk.glsl) and Eq. 25's contribution I_e F A rho / D.
// One solution per receiver point (biased where a second one exists). Every ray — the camera
// ray again, the specular prefix, the walk's start ray and the two shadow rays — goes through
// one traversal call (shaders/lib/README.md rule 4).
#include "lib/camera.glsl"
#include "lib/manifold/coplanar_walk.glsl"
#include "lib/manifold/sms.glsl"
#include "lib/rng.glsl"
#include "passes/mnee_dr/mnee_dr_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D pathImage;
layout(rgba32f) uniform writeonly image2D colorImage;
#if HAS_CAUSTIC
layout(rgba32f) uniform writeonly image2D causticImage;
#endif
#if HAS_STATS
layout(rgba32f) uniform writeonly image2D statsImage;
#endif

const uint STAGE_PREFIX = 0u;    // camera ray, then the specular prefix to the receiver
const uint STAGE_START = 1u;     // the walk's start ray (casters only)
const uint STAGE_SHADOW_P = 2u;  // receiver -> M
const uint STAGE_SHADOW_L = 3u;  // M -> light
const uint STAGE_DONE = 4u;

// Eq. 25 at a visible solution: the light's intensity towards M (area light: L_e |cos| /
// pdf_A; directional: its irradiance), the flux transmittance (1 - F) (A = 1: clear media),
// the receiver's BSDF with its cosine, over the focusing factor D.
vec3 mnee_dr_contribution(ShadingPoint sh, vec3 wo_world, ManifoldLight ml, CoplanarQuery q,
                          CoplanarResult res) {
    ManifoldChain c;
    c.k = 1u;
    c.end_at_infinity = ml.directional;
    c.v[0] = manifold_vertex(res.prim, res.bary);
    // Eq. 25 as the paper writes it: without etendue_scale, which SMS divides its point and
    // directional lights by (interpolated normals; passes/sms/README.md "Flux to radiance").
    float radiance_scale, etendue_scale;
    vec3 T = manifold_chain_throughput(c, sh.sp.p, ml.y, radiance_scale, etendue_scale);
    vec3 wi_local = shading_to_local(sh, normalize(res.M - sh.sp.p));
    vec3 f = bsdf_eval(sh.mat, shading_to_local(sh, wo_world), wi_local);
    vec3 I;
    if (ml.directional) {
        I = scene_light(ml.light).p1.rgb;
    } else if (ml.point) {
        vec3 w;
        float dist;
        I = point_light_incident(scene_light(ml.light), res.M, w, dist) * dist * dist;
    } else {
        vec3 wl = normalize(res.M - ml.y);
        I = emitted_radiance(scene_triangle(scene_light(ml.light).index).w, ml.n, -wl) *
            abs(dot(ml.n, wl));
    }
    float D = coplanar_focusing(coplanar_triangle(res.prim, q), res.bary, q);
    vec3 value = f * T * I / (radiance_scale * D * ml.pdf);
    return (!(D > 0.0) || any(isnan(value)) || any(isinf(value))) ? vec3(0.0) : value;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    // The path kernel's camera ray, retraced; the prefix and the light sample come from a
    // stream of their own (SpecularManifoldSampling's), so the path part stays the path
    // tracer's image.
    vec3 ro, rd;
    mnee_dr_camera_ray(pixel, ro, rd);
    Rng srng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x5A17C0DEu);
    vec3 u_light = vec3(rng_next2(srng), rng_next(srng));
    float rtmin = 0.0, rtmax = 1e30;
    uint rmask = BVH_MASK_ALL;
    bool rany = false;

    CoplanarSettings cs;
    cs.max_triangles = pc.maxTriangles;
    cs.max_bisections = pc.maxBisections;
    cs.bisection_tolerance = pc.bisectionTolerance;
    cs.both_directions = pc.bothDirections != 0u;

    uint stage = STAGE_PREFIX, depth = 0u, rays = 0u, status = COPLANAR_NO_START;
    uint start_attempt = 0u;
    vec3 beta = vec3(1.0), dir = rd, wo_world = vec3(0.0), ngP = vec3(0.0);
    ShadingPoint sh;
    ManifoldLight ml;
    CoplanarQuery q;
    CoplanarResult res;
    res.triangles = 0u;
    res.bisections = 0u;
    vec3 caustic = vec3(0.0);
    bool walked = false;
    for (uint n = 0u; n < pc.receiverDepth + 3u + COPLANAR_START_ATTEMPTS && stage != STAGE_DONE;
         ++n) {
        Hit hit;
        bool found = bvh_traverse(ro, rd, rtmin, rtmax, rmask, rany, hit);
        rays++;
        if (stage == STAGE_PREFIX) {
            if (!found) {
                stage = STAGE_DONE;
                continue;
            }
            sh = shading_point(hit);
            if ((bsdf_flags(sh.mat) & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u) {
                ml = manifold_sample_light(u_light);
                if (!manifold_receiver(sh.shape_flags, sh.mat) || !ml.valid) {
                    stage = STAGE_DONE;
                    continue;
                }
                wo_world = -dir;
                ngP = dot(sh.sp.ng, wo_world) < 0.0 ? -sh.sp.ng : sh.sp.ng;
                // The walk starts on the side of the receiver's surface it is seen from.
                q = coplanar_query(offset_ray_origin(sh.sp.p, ngP, ngP), ml.y, ml.directional);
                CoplanarStartRay sr;
                coplanar_start_ray(q, 0u, sr);
                ro = sr.o, rd = sr.d, rtmin = sr.tmin, rtmax = sr.tmax;
                rmask = COPLANAR_START_MASK;
                stage = STAGE_START;
                continue;
            }
            // A purely specular vertex: on along its sampled delta lobe.
            BsdfSample bs = bsdf_sample(sh.mat, shading_to_local(sh, -dir),
                                        vec3(rng_next(srng), rng_next2(srng)));
            if (depth >= pc.receiverDepth || !bsdf_sample_valid(bs)) {
                stage = STAGE_DONE;
                continue;
            }
            beta *= bsdf_sample_weight(bs);
            dir = shading_to_world(sh, bs.wi);
            ro = offset_ray_origin(sh.sp.p, sh.sp.ng, dir), rd = dir;
            depth++;
        } else if (stage == STAGE_START) {
            CoplanarStartRay sr;
            if (!found && coplanar_start_ray(q, ++start_attempt, sr)) {
                ro = sr.o, rd = sr.d, rtmin = sr.tmin, rtmax = sr.tmax;
                continue;  // the line PL further on (mirrors on the side of P and L)
            }
            res = coplanar_walk_from_start(q, cs, found, hit);
            walked = true;
            status = res.status;
            if (status != COPLANAR_SOLVED) {
                stage = STAGE_DONE;
                continue;
            }
            ManifoldVertex v = manifold_vertex(res.prim, res.bary);
            ShadowRay a = shadow_ray_between(sh.sp.p, ngP, v.p, v.ng);
            ro = a.o, rd = a.d, rtmin = 0.0, rtmax = a.tmax;
            rmask = BVH_MASK_ALL;
            rany = true;
            stage = STAGE_SHADOW_P;
        } else if (found) {  // a shadow ray is blocked
            status = COPLANAR_OCCLUDED;
            stage = STAGE_DONE;
        } else if (stage == STAGE_SHADOW_P) {
            ManifoldVertex v = manifold_vertex(res.prim, res.bary);
            ShadowRay b = ml.directional ? shadow_ray_infinite(v.p, v.ng, ml.y)
                                         : shadow_ray_between(v.p, v.ng, ml.y, ml.n);
            ro = b.o, rd = b.d, rtmin = 0.0, rtmax = b.tmax;
            stage = STAGE_SHADOW_L;
        } else {
            caustic = beta * mnee_dr_contribution(sh, wo_world, ml, q, res);
            stage = STAGE_DONE;
        }
    }
    vec4 stats = vec4(0.0);
    if (walked) {
        atomicAdd(mnee_dr_counters[COUNTER_WALKS], 1u);
        atomicAdd(mnee_dr_counters[COUNTER_STATUS + status], 1u);
        atomicAdd(mnee_dr_counters[COUNTER_TRIANGLES], res.triangles);
        atomicAdd(mnee_dr_counters[COUNTER_BISECTIONS], res.bisections);
        // Triangles crossed, bisection steps, solution found (and visible), walk run.
        stats = vec4(float(res.triangles), float(res.bisections),
                     status == COPLANAR_SOLVED ? 1.0 : 0.0, 1.0);
    }
    vec3 path = imageLoad(pathImage, ivec2(pixel)).rgb;
    imageStore(colorImage, ivec2(pixel), vec4(path + caustic, 1.0));
#if HAS_CAUSTIC
    imageStore(causticImage, ivec2(pixel), vec4(caustic, 1.0));
#endif
#if HAS_STATS
    imageStore(statsImage, ivec2(pixel), stats);
#endif
    atomicAdd(mnee_dr_counters[COUNTER_RAYS], rays);
    atomicMax(mnee_dr_counters[COUNTER_MAX_STEPS], bvh_iterations);
}
