// Uniform sampling of the solid angle subtended by a triangle (Arvo 1995, "Stratified Sampling
// of Spherical Triangles", Sec. 3), with the area-sampling fallback pbrt-v4 uses for triangles
// subtending tiny or nearly hemispherical solid angles, where the spherical construction loses
// precision.
#ifndef LOOM_SPHERICAL_TRIANGLE_GLSL
#define LOOM_SPHERICAL_TRIANGLE_GLSL

#include "lib/sampling.glsl"

const float kMinSphericalArea = 3e-4;
const float kMaxSphericalArea = 6.22;

// Solid angle of triangle (a, b, c) seen from p (Van Oosterom & Strackee 1983).
float spherical_triangle_area(vec3 p, vec3 a, vec3 b, vec3 c) {
    vec3 A = normalize(a - p), B = normalize(b - p), C = normalize(c - p);
    float num = abs(dot(A, cross(B, C)));
    float den = 1.0 + dot(A, B) + dot(B, C) + dot(C, A);
    return 2.0 * atan(num, den);
}

bool use_spherical_sampling(float omega) {
    return omega >= kMinSphericalArea && omega <= kMaxSphericalArea;
}

// Arvo's sampler: returns a unit direction from p towards the triangle; pdf = 1 / omega.
vec3 sample_spherical_triangle(vec3 p, vec3 a, vec3 b, vec3 c, vec2 u, out float omega) {
    vec3 A = normalize(a - p), B = normalize(b - p), C = normalize(c - p);
    // Normals of the great circles through the edges, and the interior angles.
    vec3 n_ab = cross(A, B), n_bc = cross(B, C), n_ca = cross(C, A);
    float l_ab = length(n_ab), l_bc = length(n_bc), l_ca = length(n_ca);
    n_ab /= l_ab;
    n_bc /= l_bc;
    n_ca /= l_ca;
    float alpha = acos(clamp(dot(n_ab, -n_ca), -1.0, 1.0));
    float beta = acos(clamp(dot(n_bc, -n_ab), -1.0, 1.0));
    float gamma = acos(clamp(dot(n_ca, -n_bc), -1.0, 1.0));
    omega = alpha + beta + gamma - PI;

    // Sub-triangle area A' = u0 * omega defines the point C' on arc AC (Arvo Eq. 5-9).
    float area_sub = u.x * omega;
    float s = sin(area_sub - alpha), t = cos(area_sub - alpha);
    float cos_alpha = cos(alpha), sin_alpha = sin(alpha);
    float cos_c = dot(A, B);
    float uu = t - cos_alpha;
    float vv = s + sin_alpha * cos_c;
    float q = ((vv * t - uu * s) * cos_alpha - vv) / ((vv * s + uu * t) * sin_alpha);
    q = clamp(q, -1.0, 1.0);
    vec3 c_perp = C - dot(C, A) * A;
    float lc = length(c_perp);
    vec3 C2 = q * A + sqrt(max(0.0, 1.0 - q * q)) * (lc > 0.0 ? c_perp / lc : vec3(0.0));
    // Uniform in z along the arc from B to C' (Arvo Eq. 10).
    float z = 1.0 - u.y * (1.0 - dot(C2, B));
    vec3 c2_perp = C2 - dot(C2, B) * B;
    float lc2 = length(c2_perp);
    return z * B + sqrt(max(0.0, 1.0 - z * z)) * (lc2 > 0.0 ? c2_perp / lc2 : vec3(0.0));
}

#endif
