#version 460
// Reservoir splatting, step 1 of the scatter (Liu et al. 2025, Sec. 4.1-4.2): every previous
// pixel's sample keeps its primary hit x1 (triangle + barycentrics) and lens sample and is
// projected into this frame's camera (multi_scatter: once per time partition, Sec. 4.4). Behind the camera, off the film or x1 occluded: rejected;
// else it lands in the pixel it now belongs to, counted there with an atomic (its rank = slot).
#include "lib/bvh.glsl"
#include "lib/camera.glsl"
#include "lib/restir/primary.glsl"
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
    uint mode;
    uint timePartitions;
    uint ablation;
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
    for (uint n = 0u; n < MAX_TIME_PARTITIONS; ++n) splat_records[idx * MAX_TIME_PARTITIONS + n] = rec;
    if (pc.historyReset != 0u || !restir_same_rules(settings_prev, settings_in) ||
        settings_in.area == 0u || !(rq.W > 0.0))
        return;
    RestirSettings cfg = settings_in;
    // Multi-splat time partitions (Sec. 4.4): only samples that carry a time can be spread.
    uint K = pc.mode == MODE_MULTI_SCATTER && restir_has_time(cfg) ? pc.timePartitions : 1u;
    atomicAdd(splat_sources, K);
    vec2 u_lens = rq.s.film_lens.zw;
    // One traversal site: step 0 traces the sample's own primary ray in the previous frame (its
    // x1, as every earlier stage traced it); step 1 + n checks x1's visibility from this frame's
    // lens point at partition n's time, in this frame's geometry.
    CameraPose pose_prev = restir_sample_pose(cfg, rq.s, true);
    CameraFrame cam_prev = camera_frame(pose_prev, pose_prev, 0.0);
    vec3 o, d;
    camera_ray(cam_prev, (vec2(q) + rq.s.film_lens.xy) / vec2(pc.frameSize), u_lens, o, d);
    float tmax = 1e30;
    FilmProjection from, to;
    SurfacePoint xp, xc;
    bool front = false;
    for (uint step = 0u; step <= K; ++step) {
        bool visibility = step > 0u;
        uint status = SPLAT_OCCLUDED;
        if (visibility) {
            // Partition n = step - 1: where x1 lands at time (n + u) / K.
            PathSample sn = rq.s;
            sn.time = splat_time_forward(rq.s.time, step - 1u, K);
            CameraPose pose_n = restir_sample_pose(cfg, sn, false);
            // x1 in this frame at that time (shapes moving over the shutter move it).
            if (sn.time != rq.s.time) xc = surface_point(rec.prim, rec.bary);
            if (!front || !splat_project(pose_n, u_lens, xc.p, xc.ng, pc.frameSize, to) ||
                !film_on_screen(to.film, pc.frameSize)) {
                status = SPLAT_OFF_SCREEN;
            } else {
                ShadowRay sr = shadow_ray_between(to.lens_point, vec3(0.0), xc.p, xc.ng);
                o = sr.o;
                d = sr.d;
                tmax = sr.tmax;
            }
        }
        if (visibility && status == SPLAT_OFF_SCREEN) {
            atomicAdd(splat_off_screen, 1u);
        } else {
            scene_select_frame(!visibility);
            Hit hit;
            bool found = bvh_traverse(o, d, 0.0, tmax, BVH_MASK_ALL, visibility, hit);
            scene_select_frame(false);
            if (!visibility) {
                if (!found) {
                    // No x1: not a path sample (its splats count as occluded).
                    atomicAdd(splat_occluded, K);
                    break;
                }
                rec.prim = hit.prim;
                rec.bary = hit.bary;
                scene_select_frame(true);
                xp = surface_point(hit.prim, hit.bary);
                scene_select_frame(false);
                xc = surface_point(hit.prim, hit.bary);
                front = splat_project(pose_prev, u_lens, xp.p, xp.ng, pc.frameSize, from);
                continue;
            }
            float J = splat_jacobian(from, xp.area, to, xc.area);
            if (pc.ablation != ABLATION_NO_TIME_JACOBIAN) J /= float(K);
            if (found) {
                atomicAdd(splat_occluded, 1u);
            } else if (!(J > 0.0 && !isinf(J))) {
                atomicAdd(splat_off_screen, 1u);
                status = SPLAT_OFF_SCREEN;
            } else {
                uvec2 p = min(uvec2(floor(to.film)), pc.frameSize - 1u);
                status = p.y * pc.frameSize.x + p.x;
                rec.dst_off = clamp(to.film - vec2(p), vec2(0.0), vec2(1.0 - 1e-7));
                rec.J = J;
                rec.slot = atomicAdd(splat_ranges[status].x, 1u);
                atomicAdd(splat_landed, 1u);
            }
        }
        rec.dst = status;
        splat_records[idx * MAX_TIME_PARTITIONS + step - 1u] = rec;
    }
}
