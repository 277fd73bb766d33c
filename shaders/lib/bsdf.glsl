// BSDFs of every material type: evaluation, pdf and importance sampling.
//
// Conventions (all routines):
//   - Local shading frame, z = shading normal. wo points to the previous path vertex (the
//     camera side when tracing from the camera), wi is the sampled/queried direction; both
//     point away from the surface and are unit length.
//   - bsdf_eval returns the cosine-weighted BSDF f(wo, wi) |cos theta_i| (Mitsuba style), so an
//     estimator multiplies by incident radiance only. Delta lobes are absent from bsdf_eval and
//     from bsdf_pdf (both return 0 for them); only bsdf_sample produces them.
//   - BsdfSample.f is that same quantity at the sampled wi (for a delta lobe: the lobe's
//     coefficient, e.g. F * specular), BsdfSample.pdf its solid-angle pdf (for a delta lobe: the
//     discrete probability of choosing it). The Monte Carlo weight is f / pdf
//     (bsdf_sample_weight). For non-delta samples f and pdf equal bsdf_eval and bsdf_pdf at wi,
//     where pdf is the density of the whole sampling routine (all non-delta lobes mixed).
//     A failed sample has pdf = 0, f = 0, flags = 0.
//   - Material eta = int_ior / ext_ior; the normal points to the exterior. BsdfSample.eta is
//     the relative IOR across the interface along wi (eta entering, 1 / eta leaving, 1 for
//     reflection), as Mitsuba's BSDFSample3f::eta.
//   - Transport mode: TRANSPORT_RADIANCE (paths from the camera, the default) scales refraction
//     by 1 / eta_rel^2 (Veach 1997, Sec. 5.2); TRANSPORT_IMPORTANCE (paths from lights) does
//     not. Then bsdf_eval(RADIANCE, wo, wi) / |cos wi| == bsdf_eval(IMPORTANCE, wi, wo) / |cos wo|.
//   - Opaque materials (diffuse, conductors, plastics) are black seen from below (wo.z < 0)
//     unless two-sided, in which case both directions are mirrored to the front side (Mitsuba
//     twosided). Dielectrics are two-sided by nature and ignore the flag.
//   - Roughness is the isotropic microfacet alpha; see microfacet.glsl for the sampling
//     technique of each distribution.
#ifndef LOOM_BSDF_GLSL
#define LOOM_BSDF_GLSL

#include "lib/sampling.glsl"
#include "lib/fresnel.glsl"
#include "lib/microfacet.glsl"
#include "lib/material.glsl"

const uint TRANSPORT_RADIANCE = 0u;
const uint TRANSPORT_IMPORTANCE = 1u;

// BsdfSample.flags (and bsdf_flags) bits.
const uint BSDF_REFLECTION = 1u;
const uint BSDF_TRANSMISSION = 2u;
const uint BSDF_DIFFUSE = 4u;
const uint BSDF_GLOSSY = 8u;
const uint BSDF_DELTA = 16u;
const uint BSDF_NULL = 32u;  // pass-through boundary (MATERIAL_NULL), also BSDF_DELTA

struct BsdfSample {
    vec3 wi;
    vec3 f;      // f |cos theta_i| (delta: lobe coefficient)
    float pdf;   // solid angle (delta: discrete probability); 0 = failed sample
    uint flags;
    float eta;   // relative IOR crossed along wi (1 for reflection)
};

BsdfSample bsdf_sample_none() {
    BsdfSample s;
    s.wi = vec3(0.0, 0.0, 1.0);
    s.f = vec3(0.0);
    s.pdf = 0.0;
    s.flags = 0u;
    s.eta = 1.0;
    return s;
}

BsdfSample bsdf_sample_make(vec3 wi, vec3 f, float pdf, uint flags, float eta) {
    if (!(pdf > 0.0)) return bsdf_sample_none();  // also rejects NaN
    BsdfSample s;
    s.wi = wi;
    s.f = f;
    s.pdf = pdf;
    s.flags = flags;
    s.eta = eta;
    return s;
}

bool bsdf_sample_valid(BsdfSample s) { return s.pdf > 0.0; }
vec3 bsdf_sample_weight(BsdfSample s) { return s.pdf > 0.0 ? s.f / s.pdf : vec3(0.0); }

// Union of the lobes a material can produce (e.g. skip light sampling when only delta).
uint bsdf_flags(Material m) {
    uint t = material_type(m);
    if (material_is(t, MATERIAL_DIFFUSE)) return BSDF_REFLECTION | BSDF_DIFFUSE;
    if (material_is(t, MATERIAL_DIELECTRIC)) return BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_DELTA;
    if (material_is(t, MATERIAL_ROUGH_DIELECTRIC)) return BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_GLOSSY;
    if (material_is(t, MATERIAL_CONDUCTOR)) return BSDF_REFLECTION | BSDF_DELTA;
    if (material_is(t, MATERIAL_ROUGH_CONDUCTOR)) return BSDF_REFLECTION | BSDF_GLOSSY;
    if (material_is(t, MATERIAL_PLASTIC)) return BSDF_REFLECTION | BSDF_DIFFUSE | BSDF_DELTA;
    if (material_is(t, MATERIAL_ROUGH_PLASTIC)) return BSDF_REFLECTION | BSDF_DIFFUSE | BSDF_GLOSSY;
    return BSDF_TRANSMISSION | BSDF_DELTA | BSDF_NULL;
}

bool bsdf_is_delta(Material m) { return (bsdf_flags(m) & (BSDF_DIFFUSE | BSDF_GLOSSY)) == 0u; }

vec3 bsdf_mirror(vec3 w) { return vec3(-w.x, -w.y, w.z); }

// Mirror reflection of wo about the micro-normal h (Walter 2007 Eq. 39).
vec3 bsdf_reflect(vec3 wo, vec3 h) { return 2.0 * dot(wo, h) * h - wo; }

// Refraction of wo about h (wo.h > 0) into the side of relative IOR eta, given the signed
// transmitted cosine from fresnel_dielectric (Walter 2007 Eq. 40).
vec3 bsdf_refract(vec3 wo, vec3 h, float eta, float cos_theta_t) {
    return (dot(wo, h) / eta + cos_theta_t) * h - wo / eta;
}

// ---------------------------------------------------------------------------------------------
// Lambert. f |cos| = albedo cos_i / pi; cosine-weighted sampling.

vec3 diffuse_eval(vec3 albedo, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    return albedo * (wi.z * INV_PI);
}

float diffuse_pdf(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
    return cosine_hemisphere_pdf(wi.z);
}

BsdfSample diffuse_sample(vec3 albedo, vec3 wo, vec2 u) {
    if (wo.z <= 0.0) return bsdf_sample_none();
    vec3 wi = sample_cosine_hemisphere(u);
    float pdf = cosine_hemisphere_pdf(wi.z);
    return bsdf_sample_make(wi, albedo * (wi.z * INV_PI), pdf, BSDF_REFLECTION | BSDF_DIFFUSE, 1.0);
}

// ---------------------------------------------------------------------------------------------
// Smooth dielectric: delta reflection or refraction, chosen with the Fresnel probability.

BsdfSample dielectric_sample(Material m, vec3 wo, float u, uint mode) {
    // Work on the side of wo; eta becomes the IOR ratio across the interface from there.
    bool inside = wo.z < 0.0;
    float eta = inside ? 1.0 / material_eta(m) : material_eta(m);
    vec3 w = vec3(wo.xy, abs(wo.z));
    float cos_t;
    float F = fresnel_dielectric(w.z, eta, cos_t);
    BsdfSample s;
    if (u < F) {
        s = bsdf_sample_make(bsdf_mirror(w), m.specular.rgb * F, F, BSDF_REFLECTION | BSDF_DELTA,
                             1.0);
    } else {
        // Snell: tangential part scales by 1 / eta, cos_t < 0 from fresnel_dielectric.
        vec3 wi = vec3(-w.xy / eta, cos_t);
        float scale = mode == TRANSPORT_RADIANCE ? 1.0 / (eta * eta) : 1.0;
        s = bsdf_sample_make(wi, m.transmittance.rgb * ((1.0 - F) * scale), 1.0 - F,
                             BSDF_TRANSMISSION | BSDF_DELTA, eta);
    }
    if (inside) s.wi.z = -s.wi.z;
    return s;
}

// ---------------------------------------------------------------------------------------------
// Rough dielectric (Walter et al. 2007), in the frame where wo.z > 0 and eta is the IOR ratio
// of the far side over the wo side. Reflection is chosen with probability F(wo.h).

// f |cos_i| and pdf at (wo, wi) via the generalised half vector.
void rough_dielectric_eval_pdf(Material m, vec3 wo, vec3 wi, float eta, uint mode, out vec3 f,
                               out float pdf) {
    f = vec3(0.0);
    pdf = 0.0;
    if (wo.z <= 0.0 || wi.z == 0.0) return;
    uint dist = material_distribution(m);
    float alpha = material_alpha(m);
    bool is_reflection = wi.z > 0.0;
    // Walter 2007 Eq. 13 (reflection) and Eq. 16 (refraction), oriented to +z.
    vec3 h = is_reflection ? wi + wo : wi * eta + wo;
    if (dot(h, h) == 0.0) return;  // eta = 1 straight through: no microfacet does this
    h = normalize(h.z < 0.0 ? -h : h);
    float wo_h = dot(wo, h), wi_h = dot(wi, h);
    // Back-facing microfacets contribute nothing (chi+ terms).
    if (wo_h <= 0.0 || wi_h * wi.z <= 0.0) return;
    float F = fresnel_dielectric(wo_h, eta);
    float D = microfacet_d(dist, alpha, h);
    float G = microfacet_g2(dist, alpha, wo, wi, h);
    float pm = microfacet_sample_pdf(dist, alpha, wo, h);
    if (is_reflection) {
        // Walter 2007 Eq. 20 times cos_i; Jacobian 1 / (4 |wo.h|) (Eq. 14).
        f = m.specular.rgb * (F * D * G / (4.0 * wo.z));
        pdf = F * pm / (4.0 * wo_h);
    } else {
        // Walter 2007 Eq. 21 times cos_i, written with eta_o = 1 and eta_i = eta; Jacobian
        // |wi.h| / (wi.h + wo.h / eta)^2 (Eq. 17).
        float denom = wi_h + wo_h / eta;
        float jac = abs(wi_h) / (denom * denom);
        float scale = mode == TRANSPORT_RADIANCE ? 1.0 / (eta * eta) : 1.0;
        f = m.transmittance.rgb * ((1.0 - F) * D * G * wo_h * jac * scale / wo.z);
        pdf = (1.0 - F) * pm * jac;
    }
}

BsdfSample rough_dielectric_sample_front(Material m, vec3 wo, vec3 u, float eta, uint mode) {
    uint dist = material_distribution(m);
    float alpha = material_alpha(m);
    vec3 h = microfacet_sample(dist, alpha, wo, u.yz);
    float wo_h = dot(wo, h);
    if (wo_h <= 0.0) return bsdf_sample_none();  // Beckmann: back-facing normal drawn
    float cos_t;
    float F = fresnel_dielectric(wo_h, eta, cos_t);
    float D = microfacet_d(dist, alpha, h);
    float pm = microfacet_sample_pdf(dist, alpha, wo, h);
    if (u.x < F) {
        vec3 wi = bsdf_reflect(wo, h);
        if (wi.z <= 0.0) return bsdf_sample_none();
        float G = microfacet_g2(dist, alpha, wo, wi, h);
        vec3 f = m.specular.rgb * (F * D * G / (4.0 * wo.z));
        return bsdf_sample_make(wi, f, F * pm / (4.0 * wo_h), BSDF_REFLECTION | BSDF_GLOSSY, 1.0);
    }
    vec3 wi = bsdf_refract(wo, h, eta, cos_t);
    if (wi.z >= 0.0) return bsdf_sample_none();
    float wi_h = dot(wi, h);
    float G = microfacet_g2(dist, alpha, wo, wi, h);
    float denom = wi_h + wo_h / eta;
    float jac = abs(wi_h) / (denom * denom);
    float scale = mode == TRANSPORT_RADIANCE ? 1.0 / (eta * eta) : 1.0;
    vec3 f = m.transmittance.rgb * ((1.0 - F) * D * G * wo_h * jac * scale / wo.z);
    return bsdf_sample_make(wi, f, (1.0 - F) * pm * jac, BSDF_TRANSMISSION | BSDF_GLOSSY, eta);
}

// ---------------------------------------------------------------------------------------------
// Conductors: exact complex-IOR Fresnel; rough variant is the Walter 2007 BRDF with VNDF
// sampling (pdf = D_wo(h) / (4 wo.h)).

vec3 rough_conductor_eval(Material m, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    uint dist = material_distribution(m);
    float alpha = material_alpha(m);
    vec3 h = normalize(wo + wi);
    vec3 F = fresnel_conductor(dot(wo, h), m.cond_eta.rgb, m.cond_k.rgb);
    float D = microfacet_d(dist, alpha, h);
    float G = microfacet_g2(dist, alpha, wo, wi, h);
    return m.specular.rgb * F * (D * G / (4.0 * wo.z));
}

float rough_conductor_pdf(Material m, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
    vec3 h = normalize(wo + wi);
    float pm = microfacet_sample_pdf(material_distribution(m), material_alpha(m), wo, h);
    return pm / (4.0 * dot(wo, h));
}

BsdfSample rough_conductor_sample(Material m, vec3 wo, vec2 u) {
    if (wo.z <= 0.0) return bsdf_sample_none();
    uint dist = material_distribution(m);
    float alpha = material_alpha(m);
    vec3 h = microfacet_sample(dist, alpha, wo, u);
    float wo_h = dot(wo, h);
    if (wo_h <= 0.0) return bsdf_sample_none();
    vec3 wi = bsdf_reflect(wo, h);
    if (wi.z <= 0.0) return bsdf_sample_none();
    vec3 F = fresnel_conductor(wo_h, m.cond_eta.rgb, m.cond_k.rgb);
    float D = microfacet_d(dist, alpha, h);
    float G = microfacet_g2(dist, alpha, wo, wi, h);
    float pdf = microfacet_sample_pdf(dist, alpha, wo, h) / (4.0 * wo_h);
    return bsdf_sample_make(wi, m.specular.rgb * F * (D * G / (4.0 * wo.z)), pdf,
                            BSDF_REFLECTION | BSDF_GLOSSY, 1.0);
}

BsdfSample conductor_sample(Material m, vec3 wo) {
    if (wo.z <= 0.0) return bsdf_sample_none();
    vec3 F = fresnel_conductor(wo.z, m.cond_eta.rgb, m.cond_k.rgb);
    return bsdf_sample_make(bsdf_mirror(wo), m.specular.rgb * F, 1.0, BSDF_REFLECTION | BSDF_DELTA,
                            1.0);
}

// ---------------------------------------------------------------------------------------------
// Plastic: dielectric coat (eta) over a Lambertian base, after Mitsuba 0.6 'plastic' and
// 'roughplastic' (Jakob 2010, plugin docs). The base term with internal scattering is
//   kd' (1 - F(cos_o)) (1 - F(cos_i)) / eta^2 * cos_i / pi,  kd' = kd / (1 - Fdr_int)
// (or kd / (1 - kd Fdr_int) when nonlinear), which makes a white base exactly energy
// conserving with the smooth coat. The rough coat (Weidlich & Wilkie 2007 style layering)
// adds a microfacet reflection lobe; its base term keeps the smooth-interface transmittances,
// where Mitsuba integrates rough-interface ones into precomputed tables (exact as alpha -> 0).
// Lobe choice (Mitsuba): P_spec = F_i w / (F_i w + (1 - F_i)(1 - w)), F_i = F(cos_o) and
// w = lum(specular) / (lum(specular) + lum(diffuse)).

float plastic_specular_probability(Material m, float cos_o) {
    float s = dot(m.specular.rgb, vec3(0.2126, 0.7152, 0.0722));
    float d = dot(m.diffuse.rgb, vec3(0.2126, 0.7152, 0.0722));
    float w = s + d > 0.0 ? s / (s + d) : 0.5;
    float Fi = fresnel_dielectric(cos_o, material_eta(m));
    float ps = Fi * w, pd = (1.0 - Fi) * (1.0 - w);
    return ps + pd > 0.0 ? ps / (ps + pd) : 0.0;
}

vec3 plastic_base_eval(Material m, vec3 wo, vec3 wi) {
    float eta = material_eta(m);
    float Fi = fresnel_dielectric(wo.z, eta);
    float Fo = fresnel_dielectric(wi.z, eta);
    vec3 kd = m.diffuse.rgb;
    float fdr = material_fdr_int(m);
    vec3 base = material_nonlinear(m) ? kd / (vec3(1.0) - kd * fdr) : kd / (1.0 - fdr);
    return base * ((1.0 - Fi) * (1.0 - Fo) / (eta * eta) * wi.z * INV_PI);
}

vec3 plastic_eval(Material m, vec3 wo, vec3 wi, bool rough) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 f = plastic_base_eval(m, wo, wi);
    if (rough) {
        // Coat reflection: Walter 2007 Eq. 20 with a dielectric Fresnel at wo.h.
        uint dist = material_distribution(m);
        float alpha = material_alpha(m);
        vec3 h = normalize(wo + wi);
        float F = fresnel_dielectric(dot(wo, h), material_eta(m));
        float D = microfacet_d(dist, alpha, h);
        float G = microfacet_g2(dist, alpha, wo, wi, h);
        f += m.specular.rgb * (F * D * G / (4.0 * wo.z));
    }
    return f;
}

float plastic_pdf(Material m, vec3 wo, vec3 wi, bool rough) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
    float ps = plastic_specular_probability(m, wo.z);
    float pdf = (1.0 - ps) * cosine_hemisphere_pdf(wi.z);
    if (rough) {
        vec3 h = normalize(wo + wi);
        pdf += ps * microfacet_sample_pdf(material_distribution(m), material_alpha(m), wo, h) /
               (4.0 * dot(wo, h));
    }
    return pdf;
}

BsdfSample plastic_sample(Material m, vec3 wo, vec3 u, bool rough) {
    if (wo.z <= 0.0) return bsdf_sample_none();
    float ps = plastic_specular_probability(m, wo.z);
    if (u.x < ps) {
        if (!rough) {
            float Fi = fresnel_dielectric(wo.z, material_eta(m));
            return bsdf_sample_make(bsdf_mirror(wo), m.specular.rgb * Fi, ps,
                                    BSDF_REFLECTION | BSDF_DELTA, 1.0);
        }
        vec3 h = microfacet_sample(material_distribution(m), material_alpha(m), wo, u.yz);
        if (dot(wo, h) <= 0.0) return bsdf_sample_none();
        vec3 wi = bsdf_reflect(wo, h);
        if (wi.z <= 0.0) return bsdf_sample_none();
        // Both lobes overlap: report the full BSDF and the mixture pdf (MIS-ready).
        return bsdf_sample_make(wi, plastic_eval(m, wo, wi, true), plastic_pdf(m, wo, wi, true),
                                BSDF_REFLECTION | BSDF_GLOSSY, 1.0);
    }
    vec3 wi = sample_cosine_hemisphere(u.yz);
    if (wi.z <= 0.0) return bsdf_sample_none();
    return bsdf_sample_make(wi, plastic_eval(m, wo, wi, rough), plastic_pdf(m, wo, wi, rough),
                            BSDF_REFLECTION | BSDF_DIFFUSE, 1.0);
}

// ---------------------------------------------------------------------------------------------
// Dispatch.

bool bsdf_is_opaque(uint t) {
    return !material_is(t, MATERIAL_DIELECTRIC) && !material_is(t, MATERIAL_ROUGH_DIELECTRIC) &&
           !material_is(t, MATERIAL_NULL);
}

// Two-sided opaque materials see the back side as the front: mirror both directions.
bool bsdf_flip_to_front(Material m, vec3 wo) {
    return wo.z < 0.0 && bsdf_is_opaque(material_type(m)) && material_two_sided(m);
}

// Rough dielectric from either side: mirror a below-surface configuration to the front; the
// IOR ratio inverts.
void rough_dielectric_eval_pdf_any_side(Material m, vec3 wo, vec3 wi, uint mode, out vec3 f,
                                        out float pdf) {
    float eta = wo.z < 0.0 ? 1.0 / material_eta(m) : material_eta(m);
    if (wo.z < 0.0) {
        wo.z = -wo.z;
        wi.z = -wi.z;
    }
    rough_dielectric_eval_pdf(m, wo, wi, eta, mode, f, pdf);
}

vec3 bsdf_eval(Material m, vec3 wo, vec3 wi, uint mode) {
    if (bsdf_flip_to_front(m, wo)) {
        wo.z = -wo.z;
        wi.z = -wi.z;
    }
    uint t = material_type(m);
    if (material_is(t, MATERIAL_DIFFUSE)) return diffuse_eval(m.diffuse.rgb, wo, wi);
    if (material_is(t, MATERIAL_ROUGH_CONDUCTOR)) return rough_conductor_eval(m, wo, wi);
    if (material_is(t, MATERIAL_PLASTIC)) return plastic_eval(m, wo, wi, false);
    if (material_is(t, MATERIAL_ROUGH_PLASTIC)) return plastic_eval(m, wo, wi, true);
    if (material_is(t, MATERIAL_ROUGH_DIELECTRIC)) {
        vec3 f;
        float pdf;
        rough_dielectric_eval_pdf_any_side(m, wo, wi, mode, f, pdf);
        return f;
    }
    return vec3(0.0);  // delta-only materials
}

vec3 bsdf_eval(Material m, vec3 wo, vec3 wi) { return bsdf_eval(m, wo, wi, TRANSPORT_RADIANCE); }

float bsdf_pdf(Material m, vec3 wo, vec3 wi) {
    if (bsdf_flip_to_front(m, wo)) {
        wo.z = -wo.z;
        wi.z = -wi.z;
    }
    uint t = material_type(m);
    if (material_is(t, MATERIAL_DIFFUSE)) return diffuse_pdf(wo, wi);
    if (material_is(t, MATERIAL_ROUGH_CONDUCTOR)) return rough_conductor_pdf(m, wo, wi);
    if (material_is(t, MATERIAL_PLASTIC)) return plastic_pdf(m, wo, wi, false);
    if (material_is(t, MATERIAL_ROUGH_PLASTIC)) return plastic_pdf(m, wo, wi, true);
    if (material_is(t, MATERIAL_ROUGH_DIELECTRIC)) {
        vec3 f;
        float pdf;
        rough_dielectric_eval_pdf_any_side(m, wo, wi, TRANSPORT_RADIANCE, f, pdf);
        return pdf;
    }
    return 0.0;
}

// u.x picks the lobe, u.yz the direction within it.
BsdfSample bsdf_sample(Material m, vec3 wo, vec3 u, uint mode) {
    bool flip = bsdf_flip_to_front(m, wo);
    if (flip) wo.z = -wo.z;
    uint t = material_type(m);
    BsdfSample s = bsdf_sample_none();
    if (material_is(t, MATERIAL_DIFFUSE)) {
        s = diffuse_sample(m.diffuse.rgb, wo, u.yz);
    } else if (material_is(t, MATERIAL_DIELECTRIC)) {
        s = dielectric_sample(m, wo, u.x, mode);
    } else if (material_is(t, MATERIAL_ROUGH_DIELECTRIC)) {
        if (wo.z == 0.0) return s;
        bool inside = wo.z < 0.0;
        float eta = inside ? 1.0 / material_eta(m) : material_eta(m);
        s = rough_dielectric_sample_front(m, vec3(wo.xy, abs(wo.z)), u, eta, mode);
        if (inside) s.wi.z = -s.wi.z;
    } else if (material_is(t, MATERIAL_CONDUCTOR)) {
        s = conductor_sample(m, wo);
    } else if (material_is(t, MATERIAL_ROUGH_CONDUCTOR)) {
        s = rough_conductor_sample(m, wo, u.yz);
    } else if (material_is(t, MATERIAL_PLASTIC)) {
        s = plastic_sample(m, wo, u, false);
    } else if (material_is(t, MATERIAL_ROUGH_PLASTIC)) {
        s = plastic_sample(m, wo, u, true);
    } else if (material_is(t, MATERIAL_NULL)) {
        s = bsdf_sample_make(-wo, vec3(1.0), 1.0, BSDF_TRANSMISSION | BSDF_DELTA | BSDF_NULL, 1.0);
    }
    if (flip) s.wi.z = -s.wi.z;
    return s;
}

BsdfSample bsdf_sample(Material m, vec3 wo, vec3 u) {
    return bsdf_sample(m, wo, u, TRANSPORT_RADIANCE);
}

#endif
