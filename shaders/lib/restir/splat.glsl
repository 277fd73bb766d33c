// Reservoir splatting (Liu et al. 2025, "Reservoir Splatting for Temporal Path Resampling and
// Motion Blur"): the shift that keeps a path's primary hit x1 (triangle + barycentrics, i.e.
// object space) and its lens sample and moves its film position to wherever x1 appears in another
// frame's camera; its Jacobian from film footprints (Eq. 14-16); and the MIS weights of a splatted
// prior sample and of the canonical sample with its reverse splat (Eq. 11, 13).
#ifndef LOOM_RESTIR_SPLAT_GLSL
#define LOOM_RESTIR_SPLAT_GLSL

#include "lib/camera.glsl"
#include "lib/sampling.glsl"
#include "lib/scene.glsl"

// Where a surface point appears on a camera's film through one lens point.
struct FilmProjection {
    vec2 film;        // film position in pixels (pixel + subpixel offset)
    vec3 lens_point;  // the camera vertex x0 of the lens sample
    float footprint;  // film area (pixels^2) per surface area at the point, Eq. 14
};

// The lens point of lens sample u_lens (camera_ray's; the camera centre for a pinhole).
vec3 camera_lens_point(CameraFrame c, vec2 u_lens) {
    if (c.aperture <= 0.0) return c.origin;
    vec2 l = c.aperture * sample_disk_concentric(u_lens);
    return c.origin + l.x * c.right_axis + l.y * c.up_axis;
}

// Projects point p (geometric normal ng) through the lens point of u_lens onto the film of pose:
// the film position whose camera_ray with the same lens sample passes through p. A thin lens
// focuses that ray through the focal-plane point F where the line lens point -> p crosses
// z = focus; the film position is F's direction. False when p is not in front of the lens plane.
// Footprint (Eq. 14 with the film measured in pixels): dA_film / dA_p =
//   (W H / (4 tan_x tan_y)) |cos theta_N| / (d^2 |cos theta_V|^3),
// d = |p - x0|, theta_V the angle of x0 -> p to the optical axis, theta_N to the geometric
// normal. The same for a thin lens: the central projection through x0 onto the focal plane,
// then the focal plane's linear map to the film, contribute d_F^2 cos_N / (d^2 cos_V) and
// 1 / (focus^2), with d_F = focus / cos_V.
bool splat_project(CameraPose pose, vec2 u_lens, vec3 p, vec3 ng, uvec2 frame_size,
                   out FilmProjection fp) {
    CameraFrame c = camera_frame(pose, pose, 0.0);
    fp.lens_point = camera_lens_point(c, u_lens);
    fp.film = vec2(-1.0);
    fp.footprint = 0.0;
    vec3 v = p - fp.lens_point;
    float d2 = dot(v, v), z = dot(v, c.forward);
    if (!(z > 1e-6 * sqrt(d2))) return false;
    // The film direction (camera space, z = 1) of the ray x0 -> p.
    vec2 xy = vec2(dot(v, c.right_axis), dot(v, c.up_axis)) / z;
    if (c.aperture > 0.0) {
        vec3 l = fp.lens_point - c.origin;
        xy += vec2(dot(l, c.right_axis), dot(l, c.up_axis)) / c.focus_distance;
    }
    vec2 uv = vec2(1.0 - xy.x / c.tan_half_fov.x, 1.0 - xy.y / c.tan_half_fov.y) * 0.5;
    fp.film = uv * vec2(frame_size);
    float cos_v = z * inversesqrt(d2), cos_n = abs(dot(ng, v)) * inversesqrt(d2);
    float film_scale = float(frame_size.x) * float(frame_size.y) /
                       (4.0 * c.tan_half_fov.x * c.tan_half_fov.y);
    fp.footprint = film_scale * cos_n / (d2 * cos_v * cos_v * cos_v);
    return fp.footprint > 0.0 && !isinf(fp.footprint);
}

bool film_on_screen(vec2 film, uvec2 frame_size) {
    return all(greaterThanEqual(film, vec2(0.0))) && all(lessThan(film, vec2(frame_size)));
}

// Jacobian |d film_to / d film_from| of the splat shift (Eq. 15-16): x1 keeps its barycentrics,
// so between the frames surface area scales with the triangle's area (1 for rigid motion).
float splat_jacobian(FilmProjection from, float area_from, FilmProjection to, float area_to) {
    float den = from.footprint * area_from;
    return den > 0.0 ? to.footprint * area_to / den : 0.0;
}

// Multi-splatting (Sec. 4.4): with K time partitions, the previous sample at shutter fraction u
// is splatted K times, to (n + u) / K in partition n = 0 .. K-1 (the previous shutter squeezed
// into each 1/K of this one; |du' / du| = 1/K, a factor of the splat's Jacobian).
float splat_time_forward(float u_prev, uint n, uint K) { return (float(n) + u_prev) / float(K); }
uint splat_time_partition(float u, uint K) { return min(uint(u * float(K)), K - 1u); }
float splat_time_backward(float u, uint K) {
    return clamp(u * float(K) - float(splat_time_partition(u, K)), 0.0, 1.0 - 1e-7);
}

// MIS (Eq. 11, 13) by the generalized balance heuristic over the techniques that can produce a
// path y at this pixel: the canonical one (confidence c_cur, target p_hat(y)), the prior frame's
// pixel y's reverse splat lands in (c_r, its target of T^-1(y), times J_rev = |dT^-1 / dy|) and,
// with a backup (scatter_backup), the backup pixel through the lens-vertex copy (Jacobian 1). Each
// term is confidence times target pulled back into this domain; with a backup, the scatter and
// backup confidences are halved by the caller (the prior frame would otherwise count twice).

// A prior-frame sample x_i splatted to Y = T(x_i) (Eq. 11), J = |dY / dx_i|: its own term is
// c_i t_prev / J; backup_term = c_b p_hat_b(copy of Y into the backup pixel), 0 without one.
float splat_mis_prior(float c_i, float t_prev, float c_cur, float t_cur, float J, float backup_term) {
    float own = c_i * t_prev, den = own + (c_cur * t_cur + backup_term) * J;
    return den > 0.0 ? own / den : 0.0;
}

// The canonical sample Y* (Eq. 13): t_rev = 0 when its reverse splat fails (off the previous
// film, occluded there, or the path cannot shift).
float splat_mis_canonical(float c_cur, float t_cur, float c_r, float t_rev, float J_rev,
                          float backup_term) {
    float own = c_cur * t_cur, den = own + c_r * t_rev * J_rev + backup_term;
    return den > 0.0 ? own / den : 0.0;
}

// The backup sample Y_b, copied from the backup pixel (own target t_b_prev there): against the
// canonical technique (t_cur = p_hat(Y_b)) and the prior pixel Y_b's reverse splat lands in.
float splat_mis_backup(float c_b, float t_b_prev, float c_cur, float t_cur, float c_r, float t_rev,
                       float J_rev) {
    float own = c_b * t_b_prev, den = own + c_cur * t_cur + c_r * t_rev * J_rev;
    return den > 0.0 ? own / den : 0.0;
}

#endif
