// Reuse between path reservoirs (Lin et al. 2022, Sec. 4 and 7): neighbour rejection and the
// resampling MIS weights of temporal (generalized balance, 2 techniques) and spatial (pairwise)
// reuse. Failed shifts enter as a target of 0, never as a confidence that contributed.
#ifndef LOOM_RESTIR_PATH_REUSE_GLSL
#define LOOM_RESTIR_PATH_REUSE_GLSL

#include "lib/camera.glsl"
#include "lib/restir/path_shift.glsl"

// Geometric similarity of two primary hits (a technique-set choice, independent of samples, so
// any rule is unbiased): normals within normal_threshold (cosine) and camera distances within
// depth_threshold relative.
bool restir_similar(PrimaryHit a, PrimaryHit b, float normal_threshold, float depth_threshold) {
    if (!primary_valid(a) || !primary_valid(b)) return false;
    SurfacePoint sa = surface_point(a.hit.x, uintBitsToFloat(a.hit.yz));
    SurfacePoint sb = surface_point(b.hit.x, uintBitsToFloat(b.hit.yz));
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
    CameraFrame cam = camera_frame(pose, pose, 0.0);
    vec3 o, d;
    camera_ray(cam, (vec2(pixel) + s.film_lens.xy) / vec2(cfg.frame_size), s.film_lens.zw, o, d);
    PrimaryHit ph;
    ph.camera = vec4(o, 1.0);
    Hit hit;
    if (trace_closest(o, d, 0.0, 1e30, BVH_MASK_ALL, hit))
        ph.hit = uvec4(hit.prim, floatBitsToUint(hit.bary), 0u);
    else
        ph.hit = uvec4(~0u, floatBitsToUint(d));
    return ph;
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
