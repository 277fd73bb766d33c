#version 460
// Reservoir splatting, step 1 of the scatter (Liu et al. 2025, Sec. 4.1-4.2): every previous
// pixel's sample keeps its primary hit x1 (triangle + barycentrics) and lens sample and is
// projected into this frame's camera. Behind the camera, off the film or x1 occluded: rejected;
// else it lands in the pixel it now belongs to, counted there with an atomic (its rank = slot).
#include "lib/bvh.glsl"
#include "lib/camera.glsl"
#include "lib/restir/reservoir.glsl"
#include "lib/restir/splat.glsl"
#include "lib/restir/temporal.glsl"
#include "lib/shading.glsl"
#include "passes/reservoir_splat/splat_buffers.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) readonly buffer PrevReservoirs {
    RestirSettings settings_prev;
    PathReservoir reservoirs_prev[];
};

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint historyReset;
} pc;

void main() {
    uvec2 q = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(q, pc.frameSize))) return;
    uint idx = q.y * pc.frameSize.x + q.x;
    SplatRecord rec;
    rec.dst = SPLAT_EMPTY;
    rec.slot = 0u;
    rec.dst_off = vec2(0.0);
    rec.prim = ~0u;
    rec.J = 0.0;
    rec.bary = vec2(0.0);
    PathReservoir rq = reservoirs_prev[idx];
    if (pc.historyReset != 0u || !restir_same_rules(settings_prev, settings_in) ||
        settings_in.area == 0u || !(rq.W > 0.0)) {
        splat_records[idx] = rec;
        return;
    }
    atomicAdd(splat_sources, 1u);
    vec2 u_lens = rq.s.film_lens.zw;
    // Two rays through one traversal site: the sample's own primary ray in the previous frame
    // (its x1, as every earlier stage traced it), then x1's visibility from this frame's lens
    // point in this frame's geometry.
    CameraFrame cam_prev = camera_frame(scene_info.camera_prev, scene_info.camera_prev, 0.0);
    vec3 o, d;
    camera_ray(cam_prev, (vec2(q) + rq.s.film_lens.xy) / vec2(pc.frameSize), u_lens, o, d);
    float tmax = 1e30;
    bool any_hit = false;
    uint status = SPLAT_OCCLUDED;
    FilmProjection from, to;
    float area_from = 0.0, area_to = 0.0;
    for (uint step = 0u; step < 2u; ++step) {
        scene_select_frame(step == 0u);
        Hit hit;
        bool found = bvh_traverse(o, d, 0.0, tmax, BVH_MASK_ALL, any_hit, hit);
        if (step == 1u) {
            if (!found) status = 0u;
            break;
        }
        if (!found) break;  // no x1: not a path sample (counted as occluded)
        rec.prim = hit.prim;
        rec.bary = hit.bary;
        SurfacePoint xp = surface_point(hit.prim, hit.bary);
        area_from = xp.area;
        bool front = splat_project(scene_info.camera_prev, u_lens, xp.p, xp.ng, pc.frameSize, from);
        scene_select_frame(false);
        SurfacePoint xc = surface_point(hit.prim, hit.bary);
        area_to = xc.area;
        if (!front ||
            !splat_project(scene_info.camera_open, u_lens, xc.p, xc.ng, pc.frameSize, to) ||
            !film_on_screen(to.film, pc.frameSize)) {
            status = SPLAT_OFF_SCREEN;
            break;
        }
        ShadowRay sr = shadow_ray_between(to.lens_point, vec3(0.0), xc.p, xc.ng);
        o = sr.o;
        d = sr.d;
        tmax = sr.tmax;
        any_hit = true;
    }
    scene_select_frame(false);
    float J = splat_jacobian(from, area_from, to, area_to);
    if (status == 0u && !(J > 0.0 && !isinf(J))) status = SPLAT_OFF_SCREEN;
    if (status == SPLAT_OFF_SCREEN) {
        atomicAdd(splat_off_screen, 1u);
    } else if (status == SPLAT_OCCLUDED) {
        atomicAdd(splat_occluded, 1u);
    } else {
        uvec2 p = min(uvec2(floor(to.film)), pc.frameSize - 1u);
        status = p.y * pc.frameSize.x + p.x;
        rec.dst_off = clamp(to.film - vec2(p), vec2(0.0), vec2(1.0 - 1e-7));
        rec.J = J;
        rec.slot = atomicAdd(splat_ranges[status].x, 1u);
        atomicAdd(splat_landed, 1u);
    }
    rec.dst = status;
    splat_records[idx] = rec;
}
