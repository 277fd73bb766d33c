// Specular constraints of manifold walks (Zeltner et al. 2020, "Specular Manifold Sampling for
// Rendering High-Frequency Caustics and Glints", Sec. 4.2 and 5; Hanika et al. 2015, "Manifold
// Next Event Estimation"). At a specular vertex with directions w_i (towards the previous
// vertex) and w_o (towards the next), both unit and pointing away from the vertex:
//   - angle difference (SMS default): scatter w_i about the (offset) normal n to w_io and
//     compare spherical angles, C = (theta(w_o) - theta(w_io), wrap(phi(w_o) - phi(w_io)));
//   - half vector (MNEE): C = (s.h, t.h) - o.xy with h ~ -(w_i + eta w_o).
// C = 0 exactly on the specular manifold. Derivatives and the Newton walk build on these.
#ifndef LOOM_MANIFOLD_CONSTRAINTS_GLSL
#define LOOM_MANIFOLD_CONSTRAINTS_GLSL

#include "lib/bsdf.glsl"
#include "lib/fresnel.glsl"
#include "lib/sampling.glsl"

// Wraps an angle difference into [-pi, pi]: phi jumps by 2 pi across the frame's seam, and an
// unwrapped difference there reads as a large error (the reference code's "important bug" fix).
float manifold_wrap_angle(float a) {
    return a - 2.0 * PI * floor((a + PI) / (2.0 * PI));
}

// A frame for spherical coordinates whose pole is the world axis least aligned with `w`
// (theta, phi are singular at the pole: the reference code's world z fails in Y-up scenes with
// overhead lights). Chosen once per walk, from the seed's w_o, and kept while it converges.
mat3 manifold_angle_frame(vec3 w) {
    vec3 a = abs(w);
    vec3 pole = a.x <= a.y && a.x <= a.z ? vec3(1, 0, 0) : a.y <= a.z ? vec3(0, 1, 0) : vec3(0, 0, 1);
    vec3 s, t;
    orthonormal_basis(pole, s, t);
    return mat3(s, t, pole);
}

// (theta, phi) of unit w in `frame` (columns s, t, pole).
vec2 manifold_spherical(mat3 frame, vec3 w) {
    vec3 l = transpose(frame) * w;
    return vec2(acos(clamp(l.z, -1.0, 1.0)), atan(l.y, l.x));
}

struct SpecularScatter {
    vec3 w;      // scattered direction (unit, away from the vertex)
    bool valid;  // false: refraction requested but totally internally reflected
};

// Mirror reflection of w about n (either side).
SpecularScatter specular_reflect(vec3 w, vec3 n) {
    SpecularScatter s;
    s.w = bsdf_reflect(w, n);
    s.valid = true;
    return s;
}

// Refraction of w through an interface with normal n and eta = eta_int / eta_ext (n points to
// the exterior); w may arrive from either side. Invalid under total internal reflection.
SpecularScatter specular_refract(vec3 w, vec3 n, float eta) {
    float cos_t;
    float c = dot(w, n);
    fresnel_dielectric(c, eta, cos_t);
    SpecularScatter s;
    s.valid = cos_t != 0.0;
    vec3 h = c >= 0.0 ? n : -n;
    float e = c >= 0.0 ? eta : 1.0 / eta;
    s.w = s.valid ? normalize(bsdf_refract(w, h, e, -abs(cos_t))) : vec3(0.0);
    return s;
}

// Angle-difference constraint at one specular vertex (Zeltner et al. Sec. 5.1). `reflection`
// selects mirror reflection, else refraction with eta. Under total internal reflection of w_i
// the roles swap: w_o is refracted and compared with w_i. `valid` is false when neither
// direction refracts (the configuration is not on any refraction manifold).
vec2 angle_difference_constraint(vec3 wi, vec3 wo, vec3 n, float eta, bool reflection,
                                 mat3 frame, out bool valid) {
    SpecularScatter s = reflection ? specular_reflect(wi, n) : specular_refract(wi, n, eta);
    vec3 target = wo;
    if (!s.valid) {
        s = specular_refract(wo, n, eta);
        target = wi;
    }
    valid = s.valid;
    if (!valid) return vec2(0.0);
    vec2 a = manifold_spherical(frame, target), b = manifold_spherical(frame, s.w);
    return vec2(a.x - b.x, manifold_wrap_angle(a.y - b.y));
}

// Half-vector constraint (Hanika et al. 2015, Sec. 4; Zeltner et al. Sec. 5.1): the generalized
// half vector h ~ -(w_i + eta' w_o) projected on the tangent frame (s, t) of normal n, minus the
// offset normal's tangential part o_xy (0 for smooth casters). Conductors (reflection): eta' = 1
// and h ~ w_i + w_o. eta' is eta seen from w_i's side (1 / eta from behind).
vec2 half_vector_constraint(vec3 wi, vec3 wo, vec3 n, vec3 s, vec3 t, float eta, bool reflection,
                            vec2 offset_xy) {
    vec3 h;
    if (reflection) {
        h = wi + wo;
    } else {
        float e = dot(wi, n) >= 0.0 ? eta : 1.0 / eta;
        h = -(wi + e * wo);
    }
    h = normalize(h);
    if (dot(h, n) < 0.0) h = -h;
    return vec2(dot(s, h), dot(t, h)) - offset_xy;
}

#endif
