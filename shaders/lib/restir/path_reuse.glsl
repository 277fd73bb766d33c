// Reuse between path reservoirs (Lin et al. 2022, Sec. 4 and 7): neighbour rejection and the
// resampling MIS weights of temporal (generalized balance, 2 techniques) and spatial (pairwise)
// reuse. Failed shifts enter as a target of 0, never as a confidence that contributed.
#ifndef LOOM_RESTIR_PATH_REUSE_GLSL
#define LOOM_RESTIR_PATH_REUSE_GLSL

#include "lib/camera.glsl"
#include "lib/restir/path_shift.glsl"

// Geometric similarity of two primary hits (a technique-set choice, independent of samples, so
// any rule is unbiased): normals within normal_threshold (cosine) and camera distances within
// depth_threshold relative. a is this frame's; b_previous: b is the previous frame's.
bool restir_similar(PrimaryHit a, PrimaryHit b, bool b_previous, float normal_threshold,
                    float depth_threshold) {
    if (!primary_valid(a) || !primary_valid(b)) return false;
    SurfacePoint sa = surface_point(a.hit.x, uintBitsToFloat(a.hit.yz));
    scene_select_frame(b_previous);
    SurfacePoint sb = surface_point(b.hit.x, uintBitsToFloat(b.hit.yz));
    scene_select_frame(false);
    if (dot(sa.ns, sb.ns) < normal_threshold) return false;
    float da = length(sa.p - a.camera.xyz), db = length(sb.p - b.camera.xyz);
    return abs(da - db) <= depth_threshold * max(da, db);
}

// The primary hit a sample starts from in the domain of `pixel` seen by camera `pose`. ReSTIR PT:
// the pixel's own primary hit. Area ReSTIR (Zhang et al. 2024, Sec. 4): the sample's film offset
// and lens sample are copied to the destination pixel and the primary ray is traced again;
// copying primary sample space coordinates has Jacobian 1 (box pixel filter, same lens).
PrimaryHit restir_domain_primary(RestirSettings cfg, PathSample s, PrimaryHit pixel_hit,
                                 ivec2 pixel, CameraPose pose) {
    if (cfg.area == 0u) return pixel_hit;
    atomicAdd(shift_rays, 1u);
    return restir_trace_primary(pose, pixel, s.film_lens, cfg.frame_size);
}

// Area ReSTIR shift mappings of the primary vertex under a thin lens (bit masks, dofShift).
const uint SHIFT_COPY = 1u;               // film and lens sample replayed (lens-vertex copy)
const uint SHIFT_PRIMARY_RECONNECT = 2u;  // primary hit kept, lens point solved for

// The shift masks of a dofShift choice (DOF_SHIFT_*, declared in passes/restir_pt).
uint dof_shift_mask(uint dof_shift) {
    return dof_shift == DOF_SHIFT_BOTH   ? SHIFT_COPY | SHIFT_PRIMARY_RECONNECT
           : dof_shift == DOF_SHIFT_COPY ? SHIFT_COPY
                                         : SHIFT_PRIMARY_RECONNECT;
}

// Thin-lens point on the focal plane seen through film position (pixel + offset).
vec3 camera_focal_point(CameraFrame cam, vec2 film_uv) {
    vec3 d = vec3((1.0 - 2.0 * film_uv.x) * cam.tan_half_fov.x,
                  (1.0 - 2.0 * film_uv.y) * cam.tan_half_fov.y, 1.0) * cam.focus_distance;
    return cam.origin + d.x * cam.right_axis + d.y * cam.up_axis + d.z * cam.forward;
}

// Area change of a central projection through P from a point a (normal n_a) to a point b
// (normal n_b) on the same line: dA_b / dA_a = |b - P|^2 cos_a / (|a - P|^2 cos_b).
float projection_area_ratio(vec3 P, vec3 a, vec3 n_a, vec3 b, vec3 n_b) {
    vec3 dir = normalize(b - a);
    float cos_a = abs(dot(n_a, dir)), cos_b = abs(dot(n_b, dir));
    vec3 pa = a - P, pb = b - P;
    float den = dot(pa, pa) * cos_b;
    return den > 0.0 ? dot(pb, pb) * cos_a / den : 0.0;
}

// Primary-hit reconnection for depth of field (Zhang et al. 2024, Sec. 6): keep the sample's
// primary hit x1 and pick the lens point whose ray through the focal point of the destination
// film position reaches x1. src: the sample's primary hit in its own domain (camera = its lens
// point); src_film / dst_film: film positions in pixels (pixel + subpixel offset; spatial reuse
// copies the offset, temporal reuse translates it by the motion vector); only the lens sample
// of s_dst is set. J = |d lens_y / d lens_x| (lens area, = primary sample space: the concentric
// mapping preserves area): lens_x -> x1 -> lens_y are two central projections through the
// focal points P_x and P_y. src_previous / dst_previous: the frames whose geometry the domains
// belong to (temporal reuse with moving shapes: x1 keeps its surface coordinates, and rigid
// motion keeps areas); the destination frame is left selected (scene_select_frame).
bool restir_primary_reconnect(PathSample s, PrimaryHit src, vec2 src_film, CameraPose src_pose,
                              bool src_previous, vec2 dst_film, CameraPose dst_pose,
                              bool dst_previous, uvec2 frame_size, out PathSample s_dst,
                              out PrimaryHit dst, out float J) {
    s_dst = s;
    dst = src;
    J = 0.0;
    scene_select_frame(dst_previous);
    if (!primary_valid(src)) return false;
    CameraFrame cx = camera_frame(src_pose, src_pose, 0.0);
    CameraFrame cy = camera_frame(dst_pose, dst_pose, 0.0);
    if (cy.aperture <= 0.0 || cx.aperture <= 0.0) return false;
    SurfacePoint x1 = surface_point(src.hit.x, uintBitsToFloat(src.hit.yz));
    SurfacePoint x1_src = x1;
    if (src_previous != dst_previous) {
        scene_select_frame(src_previous);
        x1_src = surface_point(src.hit.x, uintBitsToFloat(src.hit.yz));
        scene_select_frame(dst_previous);
    }
    vec3 Px = camera_focal_point(cx, src_film / vec2(frame_size));
    vec3 Py = camera_focal_point(cy, dst_film / vec2(frame_size));
    // Line Py -> x1 meets the lens plane (camera z = 0).
    vec3 P = Py - cy.origin, X = x1.p - cy.origin;
    vec3 Pc = vec3(dot(P, cy.right_axis), dot(P, cy.up_axis), dot(P, cy.forward));
    vec3 Xc = vec3(dot(X, cy.right_axis), dot(X, cy.up_axis), dot(X, cy.forward));
    if (abs(Xc.z - Pc.z) < 1e-12) return false;
    vec3 Lc = Pc + (Xc - Pc) * (-Pc.z / (Xc.z - Pc.z));
    vec2 lens = Lc.xy / cy.aperture;
    if (dot(lens, lens) >= 1.0) return false;
    s_dst.film_lens.zw = disk_concentric_inverse(lens);
    vec3 Ly = cy.origin + Lc.x * cy.right_axis + Lc.y * cy.up_axis;
    // The new primary segment must be unoccluded.
    ShadowRay primary = shadow_ray_between(Ly, vec3(0.0), x1.p, x1.ng);
    atomicAdd(shift_rays, 1u);
    if (trace_any(primary.o, primary.d, 0.0, primary.tmax, BVH_MASK_ALL)) return false;
    vec3 Lx = src.camera.xyz;
    J = projection_area_ratio(Px, Lx, cx.forward, x1_src.p, x1_src.ng) *
        projection_area_ratio(Py, x1.p, x1.ng, Ly, cy.forward);
    dst.camera = vec4(Ly, 1.0);
    return J > 0.0 && !isinf(J);
}

// Two-technique generalized balance heuristic with confidences (Lin et al. Eq. 11 with M_i):
// weight of technique a for a sample whose targets are t_a (own) and t_b (shifted to b).
float mis_balance2(float M_a, float t_a, float M_b, float t_b) {
    float den = M_a * t_a + M_b * t_b;
    return den > 0.0 ? M_a * t_a / den : 0.0;
}

// Defensive pairwise MIS (Bitterli 2022, Sec. 9.1.3; Lin et al. 2022, Sec. 7.2). With k valid
// neighbours every weight is divided by k + 1:
//   neighbour q, for its shifted sample x:  m_q(x) = balance(M_q p_hat_q, M_c p_hat_c)(x)
//   canonical, for its own sample x:        m_c(x) = 1 + sum_q (1 - balance(M_q p_hat_q, M_c p_hat_c)(x))
// where p_hat_q(x) is the target of x shifted into q's domain (0 when that shift fails).
float pairwise_neighbour_weight(float M_q, float t_q, float M_c, float t_c) {
    return mis_balance2(M_q, t_q, M_c, t_c);
}
float pairwise_canonical_term(float M_q, float t_q, float M_c, float t_c) {
    return 1.0 - mis_balance2(M_q, t_q, M_c, t_c);
}

#endif
