// Next-event estimation and its MIS with BSDF sampling, shared by every estimator that samples
// lights: PathTracer, ReSTIR PT's candidate generation and shifts, and the caustic passes. A
// fix or a test of light sampling here covers all of them (tests/gpu/test_path_tracer.cpp
// checks it against closed forms that do not use this code).
//
// pdfs are solid-angle densities at the shading point and include the light-selection
// probability (lights.glsl), so the MIS weights below are Veach's heuristics on the two
// techniques' densities of the same direction.
#ifndef LOOM_INTEGRATOR_NEE_GLSL
#define LOOM_INTEGRATOR_NEE_GLSL

#include "lib/bsdf.glsl"
#include "lib/lights.glsl"
#include "lib/mis.glsl"
#include "lib/shading.glsl"

// The visibility ray of a light sample taken at p (geometric normal ng).
ShadowRay light_shadow_ray(vec3 p, vec3 ng, LightSample ls) {
    if (!(ls.dist < 1e29)) return shadow_ray_infinite(p, ng, ls.wi);
    return shadow_ray_between(p, ng, p + ls.wi * ls.dist, ls.n);
}

struct NeeSample {
    LightSample ls;
    vec3 f;          // bsdf_eval at ls.wi (cosine-weighted, Mitsuba convention)
    float bsdf_pdf;  // density of BSDF sampling towards ls.wi (0 for delta lights: unused)
    float mis;       // weight against BSDF sampling; 1 for delta lights or without MIS
    vec3 value;      // f Li mis / pdf: the contribution if the shadow ray is unoccluded
    ShadowRay ray;
    bool valid;      // false: contributes nothing whatever the visibility; trace nothing
};

// One light sample at sh (outgoing direction wo in its local frame), u = (position on the
// light, light selection). The caller traces nee.ray (one traversal call site per kernel).
NeeSample nee_sample(ShadingPoint sh, vec3 wo, vec3 u, bool use_mis, uint heuristic) {
    NeeSample s;
    s.ls = sample_light(sh.sp.p, u);
    s.f = vec3(0.0);
    s.bsdf_pdf = 0.0;
    s.mis = 1.0;
    s.value = vec3(0.0);
    s.valid = false;
    s.ray = shadow_ray_infinite(sh.sp.p, sh.sp.ng, s.ls.wi);
    if (!(s.ls.pdf > 0.0) || !any(greaterThan(s.ls.Li, vec3(0.0)))) return s;
    vec3 wi = shading_to_local(sh, s.ls.wi);
    s.f = bsdf_eval(sh.mat, wo, wi);
    if (!any(greaterThan(s.f, vec3(0.0)))) return s;
    if (!s.ls.is_delta) {
        s.bsdf_pdf = bsdf_pdf(sh.mat, wo, wi);
        if (use_mis) s.mis = mis_weight(s.ls.pdf, s.bsdf_pdf, heuristic);
    }
    s.value = s.f * s.ls.Li * (s.mis / s.ls.pdf);
    s.ray = light_shadow_ray(sh.sp.p, sh.sp.ng, s.ls);
    s.valid = true;
    return s;
}

// Emitter hits: what a BSDF-sampled ray from prev_p along d found, the surface sn (triangle
// prim) when found, else the environment. The radiance it sees:
vec3 emitter_hit_radiance(vec3 d, bool found, ShadingPoint sn) {
    if (!found) return environment_radiance(d);
    return any(greaterThan(sn.emission, vec3(0.0))) ? emitted_radiance(sn.sp.shape, sn.sp.ng, d)
                                                    : vec3(0.0);
}

// The density with which light sampling from prev_p picks the same direction, for the MIS
// weight against BSDF sampling (0 for a surface that is no light). Callers evaluate it only
// where the weight is needed.
float emitter_hit_light_pdf(vec3 prev_p, vec3 d, bool found, uint prim, ShadingPoint sn) {
    return found ? light_pdf_triangle(prev_p, prim, sn.sp.p, sn.sp.ng) : light_pdf_environment(d);
}

// MIS weight of a path's last vertex, sampled by NEE (by_nee) or found by BSDF sampling, from
// both techniques' densities of it at its predecessor. Delta lights only NEE can sample.
float mis_weight_last_vertex(bool by_nee, bool delta_light, float light_pdf, float bsdf_pdf,
                             uint heuristic) {
    if (delta_light) return 1.0;
    return by_nee ? mis_weight(light_pdf, bsdf_pdf, heuristic)
                  : mis_weight(bsdf_pdf, light_pdf, heuristic);
}

#endif
