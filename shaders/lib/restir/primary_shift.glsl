// Shifts of the primary vertex (Area ReSTIR, Zhang et al. 2024): the domain a sample starts from
// at another pixel, and under a thin lens the primary-hit reconnection with its Jacobian. The
// path after the primary hit is shifted by hybrid_shift.glsl.
#ifndef LOOM_RESTIR_PRIMARY_SHIFT_GLSL
#define LOOM_RESTIR_PRIMARY_SHIFT_GLSL

#include "lib/camera.glsl"
#include "lib/restir/counters.glsl"
#include "lib/restir/primary.glsl"
#include "lib/sampling.glsl"

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

#endif
