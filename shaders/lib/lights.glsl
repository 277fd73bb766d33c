// Light sampling for next-event estimation: pick a light from the power-proportional list,
// then sample it (triangles by solid angle, Arvo 1995). Every pdf is in solid angle at the
// shading point and includes the selection probability, so MIS with BSDF sampling is direct.
#ifndef LOOM_LIGHTS_GLSL
#define LOOM_LIGHTS_GLSL

#include "lib/scene.glsl"
#include "lib/spherical_triangle.glsl"
#include "lib/envmap.glsl"

struct LightSample {
    vec3 wi;        // unit direction from the shading point to the light
    float dist;     // distance to the sampled point (1e30 for infinite lights)
    vec3 n;         // geometric normal at the sampled point (0 for point and infinite lights)
    vec3 Li;        // radiance (area/env) or intensity/dist^2 (point/spot/directional)
    float pdf;      // solid angle pdf incl. selection; 0 = failed
    bool is_delta;  // point, spot or directional light (no MIS with BSDF sampling)
    uint light;     // index of the light (scene_light)
};

uint light_count() { return scene_info.counts.z; }

// Binary search of the inclusive CDF.
uint select_light(float u) {
    uint lo = 0u, hi = light_count() - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u < scene_light_cdf[mid]) hi = mid;
        else lo = mid + 1u;
    }
    return lo;
}

// Radiance leaving an emissive triangle towards -wi (one-sided: front face only).
vec3 emitted_radiance(uint shape, vec3 n_light, vec3 wi) {
    if (dot(n_light, -wi) <= 0.0) return vec3(0.0);
    return scene_shape(shape).emission.rgb;
}

// Solid-angle pdf of sampling triangle `prim` (already selected) from p, as sample_light does.
float triangle_light_pdf(vec3 p, uint prim, vec3 p_light, vec3 n_light) {
    vec3 a, b, c;
    triangle_positions(prim, a, b, c);
    float omega = spherical_triangle_area(p, a, b, c);
    if (use_spherical_sampling(omega)) return 1.0 / omega;
    vec3 d = p_light - p;
    float dist2 = dot(d, d);
    float cos_l = abs(dot(n_light, normalize(d)));
    float area = 0.5 * length(cross(b - a, c - a));
    return cos_l > 0.0 ? dist2 / (cos_l * area) : 0.0;
}

// pdf (incl. selection) that light sampling from p would produce the emitter hit at (prim, p_light).
float light_pdf_triangle(vec3 p, uint prim, vec3 p_light, vec3 n_light) {
    ShapeGpu s = scene_shape(scene_triangle(prim).w);
    if (s.light_offset == ~0u) return 0.0;
    uint li = s.light_offset + (prim - s.first_triangle);
    return scene_light(li).pmf * triangle_light_pdf(p, prim, p_light, n_light);
}

float light_pdf_environment(vec3 wi) {
    uint li = scene_info.counts.w;
    if (li == ~0u) return 0.0;
    LightGpu l = scene_light(li);
    if (light_is(l.type, LIGHT_CONSTANT)) return l.pmf / (4.0 * PI);
    if (!light_type_present(LIGHT_ENVIRONMENT)) return 0.0;
    return l.pmf * envmap_pdf(l.index, wi);
}

// Radiance of the environment (env map or constant) seen along wi; 0 without one.
vec3 environment_radiance(vec3 wi) {
    uint li = scene_info.counts.w;
    if (li == ~0u) return vec3(0.0);
    LightGpu l = scene_light(li);
    if (light_is(l.type, LIGHT_CONSTANT)) return l.p1.rgb;
    if (!light_type_present(LIGHT_ENVIRONMENT)) return vec3(0.0);
    return l.p1.x * envmap_eval(l.index, wi);
}

// Incident radiance-equivalent (intensity / dist^2, spot falloff) at p from a point or spot
// light, with the direction and distance to it.
vec3 point_light_incident(LightGpu l, vec3 p, out vec3 wi, out float dist) {
    vec3 d = l.p0.xyz - p;
    float dist2 = dot(d, d);
    dist = sqrt(dist2);
    wi = d / dist;
    vec3 Li = l.p1.rgb / dist2;
    if (light_is(l.type, LIGHT_SPOT)) {
        // Mitsuba spot falloff: 1 inside the beam width, linear in angle to 0 at the cutoff.
        float cos_t = dot(-wi, l.p2.xyz);
        float cos_cutoff = l.p2.w, cos_beam = l.p0.w;
        float cutoff = acos(cos_cutoff), beam = acos(cos_beam);
        float fall = cos_t <= cos_cutoff ? 0.0 : cos_t >= cos_beam ? 1.0
                   : (cutoff - acos(clamp(cos_t, -1.0, 1.0))) / max(cutoff - beam, 1e-6);
        Li *= fall;
    }
    return Li;
}

LightSample sample_light(vec3 p, vec3 u) {
    LightSample ls;
    ls.pdf = 0.0;
    ls.is_delta = false;
    ls.dist = 1e30;
    ls.Li = vec3(0.0);
    ls.wi = vec3(0, 0, 1);
    ls.n = vec3(0.0);
    ls.light = 0u;
    if (light_count() == 0u) return ls;
    uint li = select_light(u.z);
    ls.light = li;
    LightGpu l = scene_light(li);
    if (light_is(l.type, LIGHT_TRIANGLE)) {
        vec3 a, b, c;
        triangle_positions(l.index, a, b, c);
        float omega = spherical_triangle_area(p, a, b, c);
        vec3 p_light;
        if (use_spherical_sampling(omega)) {
            float om;
            ls.wi = sample_spherical_triangle(p, a, b, c, u.xy, om);
            // Distance along wi to the triangle's plane.
            vec3 n = cross(b - a, c - a);
            float denom = dot(n, ls.wi);
            if (abs(denom) < 1e-20) return ls;
            ls.dist = dot(n, a - p) / denom;
            if (!(ls.dist > 0.0)) return ls;
            ls.pdf = l.pmf / omega;
        } else {
            // Uniform area sampling converted to solid angle.
            float su = sqrt(u.x);
            vec2 bary = vec2(1.0 - su, u.y * su);
            p_light = (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
            vec3 d = p_light - p;
            ls.dist = length(d);
            if (!(ls.dist > 0.0)) return ls;
            ls.wi = d / ls.dist;
            vec3 nl = normalize(cross(b - a, c - a));
            float cos_l = abs(dot(nl, ls.wi));
            float area = 0.5 * length(cross(b - a, c - a));
            if (cos_l <= 0.0 || area <= 0.0) return ls;
            ls.pdf = l.pmf * ls.dist * ls.dist / (cos_l * area);
        }
        SurfacePoint sp = surface_point(l.index, vec2(0.0));
        ls.n = sp.ng;
        ls.Li = emitted_radiance(sp.shape, sp.ng, ls.wi);
    } else if (light_is(l.type, LIGHT_POINT) || light_is(l.type, LIGHT_SPOT)) {
        ls.Li = point_light_incident(l, p, ls.wi, ls.dist);
        ls.pdf = l.pmf;
        ls.is_delta = true;
    } else if (light_is(l.type, LIGHT_DIRECTIONAL)) {
        ls.wi = l.p0.xyz;
        ls.Li = l.p1.rgb;
        ls.pdf = l.pmf;
        ls.is_delta = true;
    } else if (light_is(l.type, LIGHT_CONSTANT)) {
        ls.wi = sample_uniform_sphere(u.xy);
        ls.Li = l.p1.rgb;
        ls.pdf = l.pmf / (4.0 * PI);
    } else if (light_is(l.type, LIGHT_ENVIRONMENT)) {
        float pdf;
        ls.wi = envmap_sample(l.index, u.xy, pdf);
        ls.Li = l.p1.x * envmap_eval(l.index, ls.wi);
        ls.pdf = l.pmf * pdf;
    }
#ifdef LOOM_TEST_LIGHT_PDF_SCALE
    // Test-only: a deliberately wrong light-sampling density, so the strategy-agreement tests
    // can show that they detect a real bias in the estimator (tests/gpu/test_path_tracer.cpp).
    ls.pdf *= float(LOOM_TEST_LIGHT_PDF_SCALE);
#endif
    return ls;
}

#endif
