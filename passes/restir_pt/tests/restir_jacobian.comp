#version 460
// Test kernel: the reconnection Jacobian (solid angle) against finite differences, on random
// configurations: a small quadrilateral of directions around x_prev -> x_k is mapped through the
// plane of x_k to directions from y_prev; the ratio of the two areas is the
// Jacobian |d omega_y / d omega_x|. Also the pairwise/temporal MIS weights: for random targets
// the weights of all techniques must sum to 1. And the primary-sample-space form for cosine-
// sampled (diffuse) predecessors: |d u_y / d u_x| by central differences of the sampling map.
#include "lib/mis.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/reuse_mis.glsl"
#include "lib/rng.glsl"
#include "lib/sampling.glsl"

layout(local_size_x = 64) in;
layout(std430) writeonly buffer Results { vec4 results[]; };  // J, J_fd, pairwise sum, temporal sum
layout(std430) writeonly buffer PssResults { vec2 pss_results[]; };  // J_pss, J_pss_fd (-1 skipped)
layout(push_constant) uniform Params { uint count; uint seed; } pc;

vec3 plane_hit(vec3 o, vec3 d, vec3 p, vec3 n) { return o + d * (dot(p - o, n) / dot(d, n)); }

// Cosine-hemisphere sampling around n and its inverse (primary sample space <-> direction).
vec3 cosine_dir(vec2 u, vec3 n) { return to_world(sample_cosine_hemisphere(u), n); }
vec2 cosine_u(vec3 w, vec3 n) {
    vec3 t, b;
    orthonormal_basis(n, t, b);
    return disk_concentric_inverse(vec2(dot(w, t), dot(w, b)));
}
bool near_kink(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    return abs(abs(o.x) - abs(o.y)) < 0.02 || max(abs(o.x), abs(o.y)) > 0.98;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Rng rng = rng_init(uvec2(i, 0u), 0u, pc.seed);
    vec3 x_k = vec3(rng_next2(rng), rng_next(rng)) * 2.0 - 1.0;
    vec3 n_k = sample_uniform_sphere(rng_next2(rng));
    // Predecessors on the normal's side, not grazing.
    vec3 x_prev = x_k + (0.5 + 2.0 * rng_next(rng)) * to_world(sample_cosine_hemisphere(rng_next2(rng)), n_k);
    vec3 y_prev = x_k + (0.5 + 2.0 * rng_next(rng)) * to_world(sample_cosine_hemisphere(rng_next2(rng)), n_k);
    float J = reconnection_jacobian(x_prev, y_prev, x_k, n_k);

    vec3 w = normalize(x_k - x_prev);
    vec3 t1, t2;
    orthonormal_basis(w, t1, t2);
    // Central differences: the quadrilateral w +- eps t1, w +- eps t2 and its image; the ratio
    // of the areas spanned by the diagonals is exact to O(eps^2).
    const float eps = 2e-3;
    vec3 wa = normalize(w + eps * t1), wb = normalize(w - eps * t1);
    vec3 wc = normalize(w + eps * t2), wd = normalize(w - eps * t2);
    vec3 ua = normalize(plane_hit(x_prev, wa, x_k, n_k) - y_prev);
    vec3 ub = normalize(plane_hit(x_prev, wb, x_k, n_k) - y_prev);
    vec3 uc = normalize(plane_hit(x_prev, wc, x_k, n_k) - y_prev);
    vec3 ud = normalize(plane_hit(x_prev, wd, x_k, n_k) - y_prev);
    vec3 u0 = normalize(x_k - y_prev);
    float J_fd = length(cross(ua - ub, uc - ud)) / length(cross(wa - wb, wc - wd));
    bool grazing = abs(dot(n_k, w)) < 0.1 || abs(dot(n_k, u0)) < 0.1;

    // MIS: k neighbours with random confidences and targets of one sample x in each domain
    // (some 0: failed shifts).
    uint k = 1u + uint(rng_next(rng) * 6.0);
    float M_c = 1.0 + 19.0 * rng_next(rng);
    float t_c = rng_next(rng) < 0.1 ? 0.0 : rng_next(rng);
    float sum = 0.0, m_c = 1.0;
    for (uint q = 0u; q < k; ++q) {
        float M_q = 1.0 + 19.0 * rng_next(rng);
        float t_q = rng_next(rng) < 0.3 ? 0.0 : rng_next(rng);
        sum += pairwise_neighbour_weight(M_q, t_q, M_c, t_c);
        m_c += pairwise_canonical_term(M_q, t_q, M_c, t_c);
    }
    float pairwise_sum = (sum + m_c) / float(k + 1u);
    float M_p = 20.0 * rng_next(rng), t_p = rng_next(rng);
    float temporal_sum = (t_c > 0.0 || t_p > 0.0)
                             ? mis_balance2(M_c, t_c, M_p, t_p) + mis_balance2(M_p, t_p, M_c, t_c)
                             : 1.0;
    results[i] = vec4(J, grazing ? -1.0 : J_fd, pairwise_sum, temporal_sum);

    // PSS form: diffuse predecessors with normals n_x, n_y facing x_k.
    vec3 n_x = cosine_dir(rng_next2(rng), w);
    vec3 n_y = cosine_dir(rng_next2(rng), u0);
    float cos_x = dot(n_x, w), cos_y = dot(n_y, u0);
    float J_pss = reconnection_jacobian_pss(J, cos_y * INV_PI, cos_x * INV_PI, 1.0, 1.0);
    vec2 ux = cosine_u(w, n_x);
    float J_pss_fd = -1.0;
    if (!grazing && cos_x > 0.1 && cos_y > 0.1 && !near_kink(ux) && !near_kink(cosine_u(u0, n_y))) {
        const float e = 1e-3 / max(1.0, sqrt(J_pss));  // smaller steps where the map stretches
        vec2 d[4];
        for (int k = 0; k < 4; ++k) {
            vec2 du = (k < 2 ? vec2(e, 0.0) : vec2(0.0, e)) * ((k & 1) == 0 ? 1.0 : -1.0);
            vec3 p = plane_hit(x_prev, cosine_dir(ux + du, n_x), x_k, n_k);
            d[k] = cosine_u(normalize(p - y_prev), n_y);
        }
        vec2 c0 = (d[0] - d[1]) / (2.0 * e), c1 = (d[2] - d[3]) / (2.0 * e);
        J_pss_fd = abs(c0.x * c1.y - c0.y * c1.x);
    }
    pss_results[i] = vec2(J_pss, J_pss_fd);
}
