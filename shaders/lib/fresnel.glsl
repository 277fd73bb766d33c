// Fresnel reflectance. Conventions: cosines are taken against the macro- or micro-normal on
// the side of the incident direction (a negative cosine means "arriving from inside");
// eta = eta_int / eta_ext, the relative IOR of the side the normal points away from.
#ifndef LOOM_FRESNEL_GLSL
#define LOOM_FRESNEL_GLSL

// Exact unpolarised dielectric Fresnel with total internal reflection (pbrt-v4 FrDielectric,
// Mitsuba fresnelDielectricExt). cos_theta_t returns the signed cosine of the refracted
// direction: opposite in sign to cos_theta_i, 0 under TIR.
float fresnel_dielectric(float cos_theta_i, float eta, out float cos_theta_t) {
    cos_theta_i = clamp(cos_theta_i, -1.0, 1.0);
    // Arriving from inside: the IOR ratio across the interface inverts.
    float e = cos_theta_i >= 0.0 ? eta : 1.0 / eta;
    float ci = abs(cos_theta_i);
    // Snell's law: sin^2(theta_t) = sin^2(theta_i) / e^2.
    float sin2_t = (1.0 - ci * ci) / (e * e);
    if (sin2_t >= 1.0) {
        cos_theta_t = 0.0;
        return 1.0;  // total internal reflection
    }
    float ct = sqrt(max(0.0, 1.0 - sin2_t));
    // Fresnel equations for s- and p-polarised amplitudes (Born & Wolf 1999, Sec. 1.5.2).
    float r_s = (ci - e * ct) / (ci + e * ct);
    float r_p = (e * ci - ct) / (e * ci + ct);
    cos_theta_t = cos_theta_i >= 0.0 ? -ct : ct;
    return 0.5 * (r_s * r_s + r_p * r_p);
}

float fresnel_dielectric(float cos_theta_i, float eta) {
    float cos_theta_t;
    return fresnel_dielectric(cos_theta_i, eta, cos_theta_t);
}

// Exact conductor Fresnel for a complex IOR eta + i k per channel, light arriving from a
// dielectric exterior (Mitsuba fresnelConductorExact, after Moeller 1988, "Optics").
vec3 fresnel_conductor(float cos_theta_i, vec3 eta, vec3 k) {
    float c2 = clamp(cos_theta_i * cos_theta_i, 0.0, 1.0);
    float s2 = 1.0 - c2;
    float s4 = s2 * s2;
    vec3 t1 = eta * eta - k * k - vec3(s2);
    // a^2 + b^2 = |n^2 - sin^2|, a = Re(sqrt(n^2 - sin^2)).
    vec3 a2pb2 = sqrt(max(t1 * t1 + 4.0 * eta * eta * k * k, vec3(0.0)));
    vec3 a = sqrt(max(0.5 * (a2pb2 + t1), vec3(0.0)));
    vec3 t2 = a2pb2 + vec3(c2);
    vec3 t3 = 2.0 * abs(cos_theta_i) * a;
    vec3 r_s = (t2 - t3) / max(t2 + t3, vec3(1e-30));
    vec3 t4 = a2pb2 * c2 + vec3(s4);
    vec3 t5 = t3 * s2;
    vec3 r_p = r_s * (t4 - t5) / max(t4 + t5, vec3(1e-30));
    return 0.5 * (r_s + r_p);
}

#endif
