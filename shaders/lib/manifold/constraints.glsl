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

// (theta, phi) of unit w in `frame` (columns s, t, pole). theta by atan2, not acos: acos is
// ill-conditioned near the poles, and lavapipe's acos approximation has a slope 7e-4 off in
// relative terms, which a Newton walk's finite-difference test sees.
vec2 manifold_spherical(mat3 frame, vec3 w) {
    vec3 l = transpose(frame) * w;
    return vec2(atan(length(l.xy), l.z), atan(l.y, l.x));
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

// The same at positions: w_i = x_prev - x and w_o = x_next - x, normalized.
vec2 angle_difference_constraint_at(vec3 x_prev, vec3 x, vec3 x_next, vec3 n, float eta,
                                    bool reflection, mat3 frame, out bool valid) {
    return angle_difference_constraint(normalize(x_prev - x), normalize(x_next - x), n, eta,
                                       reflection, frame, valid);
}

// Derivative of w = d / |d| along dd.
vec3 manifold_d_normalize(vec3 w, float len, vec3 dd) { return (dd - w * dot(w, dd)) / len; }

// Derivative of (theta, phi) of unit w along dw: dtheta = -dl_z / sin(theta),
// dphi = (l_x dl_y - l_y dl_x) / sin^2(theta), l = w in `frame`.
vec2 manifold_d_spherical(mat3 frame, vec3 w, vec3 dw) {
    vec3 l = transpose(frame) * w, dl = transpose(frame) * dw;
    float sin2 = max(l.x * l.x + l.y * l.y, 1e-12);
    return vec2(-dl.z / sqrt(sin2), (l.x * dl.y - l.y * dl.x) / sin2);
}

// Derivative of the specular scattering of w about n (specular_reflect / specular_refract)
// along (dw, dn), with dn tangent to n. Refraction: w_s = (c_i/e - c_t) h - w/e with
// c_i = w.h, c_t = sqrt(1 - (1 - c_i^2)/e^2), so dc_t = c_i dc_i / (e^2 c_t).
vec3 specular_scatter_derivative(vec3 w, vec3 n, float eta, bool reflection, vec3 ws, vec3 dw,
                                 vec3 dn) {
    vec3 d;
    if (reflection) {
        float c = dot(w, n);
        d = 2.0 * (dot(dw, n) + dot(w, dn)) * n + 2.0 * c * dn - dw;
    } else {
        float c = dot(w, n);
        vec3 h = c >= 0.0 ? n : -n, dh = c >= 0.0 ? dn : -dn;
        float e = c >= 0.0 ? eta : 1.0 / eta;
        float ci = dot(w, h), dci = dot(dw, h) + dot(w, dh);
        float ct = sqrt(max(1.0 - (1.0 - ci * ci) / (e * e), 1e-12));
        float dct = ci * dci / (e * e * ct);
        d = (dci / e - dct) * h + (ci / e - ct) * dh - dw / e;
    }
    return d - ws * dot(ws, d);
}

// Directional derivative of angle_difference_constraint_at when the vertices move by dx_prev,
// dx, dx_next and the normal at x by dn (e.g. dp/du and dn/du of a SurfacePoint): the Jacobian
// blocks dC/du, dC/dv of a manifold walk's Newton step are such derivatives.
vec2 angle_difference_constraint_derivative(vec3 x_prev, vec3 x, vec3 x_next, vec3 n, float eta,
                                            bool reflection, mat3 frame, vec3 dx_prev, vec3 dx,
                                            vec3 dn, vec3 dx_next) {
    vec3 di = x_prev - x, dout = x_next - x;
    vec3 wi = normalize(di), wo = normalize(dout);
    vec3 dwi = manifold_d_normalize(wi, length(di), dx_prev - dx);
    vec3 dwo = manifold_d_normalize(wo, length(dout), dx_next - dx);
    SpecularScatter s = reflection ? specular_reflect(wi, n) : specular_refract(wi, n, eta);
    vec3 from = wi, dfrom = dwi, target = wo, dtarget = dwo;
    if (!s.valid) {  // total internal reflection: w_o is refracted and compared with w_i
        s = specular_refract(wo, n, eta);
        from = wo;
        dfrom = dwo;
        target = wi;
        dtarget = dwi;
    }
    if (!s.valid) return vec2(0.0);
    vec3 ds = specular_scatter_derivative(from, n, eta, reflection, s.w, dfrom, dn);
    return manifold_d_spherical(frame, target, dtarget) - manifold_d_spherical(frame, s.w, ds);
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

// Directional derivative of half_vector_constraint when w_i, w_o and the tangent frame (s, t)
// move by dwi, dwo, ds, dt (the side of w_i, hence eta', is fixed): h = H / |H| with
// H = w_i + w_o or -(w_i + eta' w_o), dh = (dH - h (h.dH)) / |H|.
vec2 half_vector_constraint_derivative(vec3 wi, vec3 wo, vec3 n, vec3 s, vec3 t, float eta,
                                       bool reflection, vec3 dwi, vec3 dwo, vec3 ds, vec3 dt) {
    vec3 H, dH;
    if (reflection) {
        H = wi + wo;
        dH = dwi + dwo;
    } else {
        float e = dot(wi, n) >= 0.0 ? eta : 1.0 / eta;
        H = -(wi + e * wo);
        dH = -(dwi + e * dwo);
    }
    float len = length(H);
    vec3 h = H / len;
    vec3 dh = (dH - h * dot(h, dH)) / len;
    if (dot(h, n) < 0.0) {
        h = -h;
        dh = -dh;
    }
    return vec2(dot(ds, h) + dot(s, dh), dot(dt, h) + dot(t, dh));
}

#endif
