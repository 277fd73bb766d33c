// Isotropic microfacet distributions in the local shading frame (z = macro-normal).
// Every function expects the micro-normal m in the upper hemisphere; callers working below the
// surface (dielectric interiors) mirror their frame first (see bsdf.glsl).
//   D       Walter et al. 2007, "Microfacet Models for Refraction through Rough Surfaces"
//   Lambda  Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs"
//   VNDF    Heitz 2018, "Sampling the GGX Distribution of Visible Normals"
// Sampling: GGX draws visible normals (pdf = D_wo(m), Heitz 2018 Eq. 3); Beckmann draws the
// distribution of normals D(m) cos(theta_m) (Walter 2007 Eq. 28), not its VNDF, so Beckmann
// samples can land on back-facing microfacets and then fail (the caller returns pdf 0).
#ifndef LOOM_MICROFACET_GLSL
#define LOOM_MICROFACET_GLSL

#include "lib/sampling.glsl"

const uint MICROFACET_GGX = 0u;
const uint MICROFACET_BECKMANN = 1u;

// Below this alpha the float evaluation of D overflows; Mitsuba clamps at the same value.
const float MICROFACET_MIN_ALPHA = 1e-4;

// Normal distribution D(m), normalised so that the projected area integrates to one:
// integral of D(m) cos(theta_m) dm = 1.
float microfacet_d(uint dist, float alpha, vec3 m) {
    if (m.z <= 0.0) return 0.0;
    float a2 = alpha * alpha;
    float z2 = m.z * m.z;
    float s2 = m.x * m.x + m.y * m.y;  // sin^2, from x and y to avoid 1 - z^2 cancellation
    if (dist == MICROFACET_GGX) {
        // Walter 2007 Eq. 33 rewritten: alpha^2 / (pi (alpha^2 cos^2 + sin^2)^2).
        float d = a2 * z2 + s2;
        return a2 / (PI * d * d);
    }
    // Beckmann, Walter 2007 Eq. 25: exp(-tan^2 / alpha^2) / (pi alpha^2 cos^4).
    return exp(-s2 / (z2 * a2)) / (PI * a2 * z2 * z2);
}

// Complementary error function, Abramowitz & Stegun 7.1.26 (|error| < 1.5e-7), x >= 0.
float microfacet_erfc(float x) {
    float t = 1.0 / (1.0 + 0.3275911 * x);
    float poly = t * (0.254829592 +
                      t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    return poly * exp(-x * x);
}

// Smith Lambda(w) (Heitz 2014): GGX (sqrt(1 + alpha^2 tan^2) - 1) / 2; Beckmann exact,
// (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2 with a = 1 / (alpha tan), instead of the rational
// fit of Walter 2007 Eq. 27.
float microfacet_lambda(uint dist, float alpha, vec3 w) {
    float z2 = w.z * w.z;
    float s2 = w.x * w.x + w.y * w.y;
    if (s2 <= 0.0) return 0.0;          // normal incidence: nothing is masked
    if (z2 <= 0.0) return 1e30;         // grazing: everything is masked
    float a2tan2 = alpha * alpha * s2 / z2;
    if (dist == MICROFACET_GGX) return 0.5 * (sqrt(1.0 + a2tan2) - 1.0);
    float a = inversesqrt(a2tan2);      // a = 1 / (alpha tan(theta))
    if (a > 8.0) return 0.0;            // below float resolution of the terms
    return 0.5 * (exp(-a * a) / (a * sqrt(PI)) - microfacet_erfc(a));
}

// Smith masking G1(w, m) = chi+(w.m / w.z) / (1 + Lambda(w)) (Walter 2007).
float microfacet_g1(uint dist, float alpha, vec3 w, vec3 m) {
    if (dot(w, m) * w.z <= 0.0) return 0.0;
    return 1.0 / (1.0 + microfacet_lambda(dist, alpha, w));
}

// Height-correlated masking-shadowing (Heitz 2014 Eq. 99). Used for reflection and, as in
// pbrt-v4, for transmission; wo and wi must each face m from their own side.
float microfacet_g2(uint dist, float alpha, vec3 wo, vec3 wi, vec3 m) {
    if (dot(wo, m) * wo.z <= 0.0 || dot(wi, m) * wi.z <= 0.0) return 0.0;
    return 1.0 / (1.0 + microfacet_lambda(dist, alpha, wo) + microfacet_lambda(dist, alpha, wi));
}

// Heitz 2018, Appendix A listing: GGX visible normal for wo (wo.z > 0), isotropic alpha.
vec3 microfacet_sample_ggx_vndf(float alpha, vec3 wo, vec2 u) {
    // Stretch the view vector to the hemisphere configuration (alpha = 1).
    vec3 vh = normalize(vec3(alpha * wo.x, alpha * wo.y, wo.z));
    // Orthonormal basis around vh.
    float len2 = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = len2 > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(len2) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    // Uniform disk point, warped onto the visible half of the projected disk.
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    // Reproject onto the hemisphere, then unstretch.
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
}

// Walter 2007 Eq. 28: Beckmann normals with density D(m) cos(theta_m).
vec3 microfacet_sample_beckmann_normals(float alpha, vec2 u) {
    float tan2 = -alpha * alpha * log(1.0 - u.x);
    float cos_t = inversesqrt(1.0 + tan2);
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = 2.0 * PI * u.y;
    return vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Micro-normals with density D(m) cos(theta_m), independent of any direction (the offset
// normals of rough manifold walks, which must stay fixed while the directions change):
// Beckmann by Walter 2007 Eq. 28, GGX by Eq. 35 and 36 (tan^2 = alpha^2 u / (1 - u)).
vec3 microfacet_sample_normals(uint dist, float alpha, vec2 u) {
    if (dist != MICROFACET_GGX) return microfacet_sample_beckmann_normals(alpha, u);
    float tan2 = alpha * alpha * u.x / max(1.0 - u.x, 1e-12);
    float cos_t = inversesqrt(1.0 + tan2);
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = 2.0 * PI * u.y;
    return vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Micro-normal for wo (wo.z > 0) with the technique named in the header.
vec3 microfacet_sample(uint dist, float alpha, vec3 wo, vec2 u) {
    if (dist == MICROFACET_GGX) return microfacet_sample_ggx_vndf(alpha, wo, u);
    return microfacet_sample_beckmann_normals(alpha, u);
}

// Solid-angle density over m of microfacet_sample (wo.z > 0, m.z > 0).
float microfacet_sample_pdf(uint dist, float alpha, vec3 wo, vec3 m) {
    float d = microfacet_d(dist, alpha, m);
    // Heitz 2018 Eq. 3: D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z.
    if (dist == MICROFACET_GGX)
        return microfacet_g1(dist, alpha, wo, m) * max(dot(wo, m), 0.0) * d / wo.z;
    return d * m.z;
}

#endif
