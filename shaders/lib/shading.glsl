// From a BVH hit to everything a shading kernel needs: the surface point, the material with
// its textures resolved, and the (normal-mapped) shading frame.
#ifndef LOOM_SHADING_GLSL
#define LOOM_SHADING_GLSL

#include "lib/bvh.glsl"
#include "lib/material.glsl"
#include "lib/scene.glsl"

layout(rgba32ui) uniform readonly uimage2D scene_material_texels;  // Material: 7 texels
Material scene_material(uint i) {
    uint t = 7u * i;
    Material m;
    m.diffuse = SCENE_TEXEL_F(scene_material_texels, t);
    m.specular = SCENE_TEXEL_F(scene_material_texels, t + 1u);
    m.transmittance = SCENE_TEXEL_F(scene_material_texels, t + 2u);
    m.cond_eta = SCENE_TEXEL_F(scene_material_texels, t + 3u);
    m.cond_k = SCENE_TEXEL_F(scene_material_texels, t + 4u);
    m.info = SCENE_TEXEL(scene_material_texels, t + 5u);
    m.textures = SCENE_TEXEL(scene_material_texels, t + 6u);
    return m;
}

struct ShadingPoint {
    SurfacePoint sp;
    vec3 n;         // shading normal (after normal mapping; sp.dn_du/dv are of sp.ns, before it)
    vec3 t, b;      // shading frame tangents
    Material mat;
    uint shape_flags;
    vec3 emission;  // shape radiance (0 when not a light)
};

// Evaluates surface points and traces rays in the previous frame's geometry (moving shapes;
// temporal reuse) or in this frame's (the default). Everything else is the same in both frames.
void scene_select_frame(bool previous) {
    uvec4 g = previous ? scene_info.previous_geometry : uvec4(0u);
    scene_vertex_base = g.x;
    bvh_node_base = g.y;
    bvh_tri_base = g.z;
    bvh_motion_offset = previous && g.z != 0u ? scene_info.motion.z : scene_info.motion.y;
}

// Rays and surface points from now on see shapes that move over the shutter at shutter
// fraction `time` (0 = open, the default; cameras take theirs from camera_frame). Kernels
// that sample a time per path call this before tracing it.
void scene_set_time(float time) {
    scene_time = time;
    bvh_time = time;
    bvh_motion_offset = bvh_tri_base != 0u ? scene_info.motion.z : scene_info.motion.y;
}

vec3 shading_to_local(ShadingPoint s, vec3 w) { return vec3(dot(w, s.t), dot(w, s.b), dot(w, s.n)); }
vec3 shading_to_world(ShadingPoint s, vec3 w) { return w.x * s.t + w.y * s.b + w.z * s.n; }

// The tangent frame (t, b) about the shading normal n: dp/du made orthogonal to n
// (Gram-Schmidt), or any frame where dp/du is along n.
void shading_tangent_frame(vec3 n, vec3 tangent, out vec3 t, out vec3 b) {
    vec3 a = tangent - n * dot(n, tangent);
    float len = length(a);
    if (len > 1e-12) {
        t = a / len;
        b = cross(n, t);
    } else {
        orthonormal_basis(n, t, b);
    }
}

// Tangent-space normal map (Mitsuba normalmap): the bilinear texel value holds the normal in
// the frame (t, b, n) of the interpolated normal n, as 2 rgb - 1, or, for maps read as slopes
// (the SMS normalmap's use_slopes; MaterialGpu.h normalMapSlopeTexel), as (n.x / n.z, n.y / n.z,
// 1) itself, so that slopes are what the lookup interpolates. Manifold walks differentiate the
// same expressions (manifold/walk.glsl manifold_normal_map).
vec3 normal_map_tangent_normal(Material m, vec3 texel) {
    return material_normal_slopes(m) ? texel : 2.0 * texel - 1.0;
}

vec3 normal_map_normal(vec3 nt, vec3 n, vec3 t, vec3 b) {
    return normalize(nt.x * t + nt.y * b + nt.z * n);
}

ShadingPoint shading_point(Hit hit) {
    ShadingPoint s;
    s.sp = surface_point(hit.prim, hit.bary);
    ShapeGpu shape = scene_shape(s.sp.shape);
    s.shape_flags = shape.flags;
    s.emission = shape.emission.rgb;
    s.mat = scene_material(shape.material);
    uint tex = material_reflectance_texture(s.mat);
    if (tex != MATERIAL_NO_TEXTURE) s.mat.diffuse.rgb = texture_fetch(tex, s.sp.uv).rgb;
    uint spec_tex = material_specular_texture(s.mat);
    if (spec_tex != MATERIAL_NO_TEXTURE) s.mat.specular.rgb = texture_fetch(spec_tex, s.sp.uv).rgb;
    s.n = s.sp.ns;
    shading_tangent_frame(s.n, s.sp.tangent, s.t, s.b);
    uint nmap = material_normal_map(s.mat);
    if (nmap != MATERIAL_NO_TEXTURE) {
        vec3 nt = normal_map_tangent_normal(s.mat, texture_fetch(nmap, s.sp.uv).rgb);
        vec3 n = normal_map_normal(nt, s.n, s.t, s.b);
        if (!any(isnan(n)) && !any(isinf(n))) {
            s.n = n;
            vec3 t2 = s.t - s.n * dot(s.n, s.t);
            s.t = normalize(t2);
            s.b = cross(s.n, s.t);
        }
    }
    return s;
}

// Origin offset along the geometric normal to the side of `dir`, scaled with the magnitude of
// p so self-intersection is avoided at any scene scale.
vec3 offset_ray_origin(vec3 p, vec3 ng, vec3 dir) {
    float eps = 1e-4 * max(1.0, max(abs(p.x), max(abs(p.y), abs(p.z))));
    return p + (dot(ng, dir) >= 0.0 ? eps : -eps) * ng;
}

// A visibility ray: hits with t in (0, tmax] along d from o mean "occluded".
struct ShadowRay {
    vec3 o;
    vec3 d;
    float tmax;
};

// The segment between p and q with both ends moved off their surfaces (pbrt-v4's SpawnRayTo
// from both sides); ng or nq = 0 marks a point on no surface (a lens, a point light), which
// stays put. Offsetting only the near end is not enough: its offset shortens the distance to
// q's plane by up to eps / cos, and once that exceeds the relative shadow epsilon (q nearer
// than about eps / 1e-4) q's own triangle occludes it. That was the path tracer's NEE bias
// (4-6% dark), which hit points within ~1 unit of a light, such as the Cornell box's tall block top.
ShadowRay shadow_ray_between(vec3 p, vec3 ng, vec3 q, vec3 nq) {
    ShadowRay r;
    r.o = offset_ray_origin(p, ng, q - p);
    vec3 v = offset_ray_origin(q, nq, p - q) - r.o;
    float len = length(v);
    r.d = len > 0.0 ? v / len : vec3(0.0, 0.0, 1.0);
    r.tmax = len * (1.0 - 1e-4);
    return r;
}

// Towards a light at infinity (environment, directional).
ShadowRay shadow_ray_infinite(vec3 p, vec3 ng, vec3 dir) {
    ShadowRay r;
    r.o = offset_ray_origin(p, ng, dir);
    r.d = dir;
    r.tmax = 1e30;
    return r;
}

#endif
