// The scene on the GPU (uploaded by core/scene/SceneGpu.cpp; layouts mirrored there):
// vertices, triangles, shapes, textures, the light list and the camera.
#ifndef LOOM_SCENE_GLSL
#define LOOM_SCENE_GLSL

#include "lib/camera.glsl"
#include "lib/sampling.glsl"

struct VertexGpu {
    vec4 position_u;  // xyz, uv.x
    vec4 normal_v;    // xyz (0 = none), uv.y
};
struct ShapeGpu {
    uint material;
    uint flags;           // scene::ShapeFlags
    uint light_offset;    // index of this shape's first triangle in the light list, or ~0u
    uint first_triangle;  // triangles of a shape are contiguous
    vec4 emission;        // rgb radiance, w = 1 when the shape has UVs
};
// ShapeGpu.flags, mirrored from loom::scene::ShapeFlags (Scene.h): ray visibility and the SMS
// tags of casters, receivers, bouncers and emitters.
const uint SHAPE_VISIBLE_CAMERA = 1u << 0;
const uint SHAPE_VISIBLE_SHADOW = 1u << 1;
const uint SHAPE_CAUSTIC_CASTER_REFLECT = 1u << 2;
const uint SHAPE_CAUSTIC_CASTER_REFRACT = 1u << 3;
const uint SHAPE_CAUSTIC_CASTER = SHAPE_CAUSTIC_CASTER_REFLECT | SHAPE_CAUSTIC_CASTER_REFRACT;
const uint SHAPE_CAUSTIC_RECEIVER = 1u << 4;
const uint SHAPE_CAUSTIC_EMITTER = 1u << 5;
const uint SHAPE_CAUSTIC_BOUNCER = 1u << 6;
const uint SHAPE_CAUSTIC_MULTI = 1u << 7;
struct TextureGpu {
    uint offset;  // first texel (scene_texel)
    uint width;
    uint height;
    uint kind;    // 0 bitmap, 1 checkerboard, 2 constant
    vec4 color0;
    vec4 color1;
    vec4 uv_scale;  // xy
};
// One entry per light: emissive triangles first, then point/spot/directional/environment.
struct LightGpu {
    uint type;   // LIGHT_*
    uint index;  // triangle id / texture id
    float pmf;   // selection probability
    uint flags;  // the shape's flags (triangles), else the light's (SHAPE_CAUSTIC_EMITTER)
    vec4 p0;     // point/spot: position; directional: direction towards the light
    vec4 p1;     // intensity (point/spot, W/sr), irradiance (directional), scale (env)
    vec4 p2;     // spot: axis xyz, w = cos(cutoff); p0.w = cos(beam width)
};
const uint LIGHT_TRIANGLE = 0u;
const uint LIGHT_POINT = 1u;
const uint LIGHT_SPOT = 2u;
const uint LIGHT_DIRECTIONAL = 3u;
const uint LIGHT_ENVIRONMENT = 4u;
const uint LIGHT_CONSTANT = 5u;
// The light types the scene has (bit t: LIGHT t), a compile-time constant the Renderer defines
// from its scene (SceneGpu::lightTypes; all types without one), so that the code of absent
// types is compiled out (see LOOM_SCENE_MATERIALS in material.glsl for why): dispatch on
// light types with light_is.
#ifndef LOOM_SCENE_LIGHTS
#define LOOM_SCENE_LIGHTS 0x3fu
#endif
bool light_type_present(uint t) { return ((uint(LOOM_SCENE_LIGHTS) >> t) & 1u) != 0u; }
bool light_is(uint type, uint t) { return light_type_present(t) && type == t; }

struct SceneInfo {
    CameraPose camera_open;   // this frame, shutter open
    CameraPose camera_close;  // this frame, shutter close
    CameraPose camera_prev;   // previous frame (shutter open)
    CameraPose camera_prev_close;  // previous frame (shutter close)
    uvec4 counts;             // triangles, shapes, lights, environment light index (~0u: none)
    vec4 bounds_center;       // xyz, w = bounding-sphere radius
    // The previous frame's geometry (moving shapes): base of its vertices (scene_vertex_record),
    // of its BVH in the node image and triangle records; all 0 when it is this frame's.
    uvec4 previous_geometry;
    // Motion blur of moving shapes: x = offset from a vertex to its shutter-close twin in
    // the vertex records (0: no shape moves over the shutter); y, z = bvh_motion_offset of this
    // frame's and the previous frame's tree.
    uvec4 motion;
};

// Scene records live in RGBA32UI images, texel i at (i % 8192, i / 8192) (SceneGpu's
// recordImage), read through the accessors below. On lavapipe an image load is one unrolled
// 16-byte load per lane, cheaper than a buffer load with divergent addresses (a per-lane loop
// per load instruction, and a struct loads member by member): bench/llvmpipe_loads.sh measures
// 11-14 against 17-32 ns per 16 bytes and 8-lane batch (in cache / out of it); the path tracer
// runs 1.2-1.4 times faster with the same images (bit-identical).
layout(rgba32ui) uniform readonly uimage2D scene_vertex_texels;    // VertexGpu: 2 texels
layout(rgba32ui) uniform readonly uimage2D scene_triangle_texels;  // v0, v1, v2, shape
layout(rgba32ui) uniform readonly uimage2D scene_shape_texels;     // ShapeGpu: 2 texels
layout(rgba32ui) uniform readonly uimage2D scene_texture_texels;   // TextureGpu: 4 texels
layout(rgba32ui) uniform readonly uimage2D scene_texel_texels;     // texture texels (rgba32f)
layout(rgba32ui) uniform readonly uimage2D scene_light_texels;     // LightGpu: 4 texels
#define SCENE_TEXEL(image, i) imageLoad(image, ivec2(int((i) & 8191u), int((i) >> 13u)))
#define SCENE_TEXEL_F(image, i) uintBitsToFloat(SCENE_TEXEL(image, i))

VertexGpu scene_vertex_record(uint i) {
    VertexGpu v;
    v.position_u = SCENE_TEXEL_F(scene_vertex_texels, 2u * i);
    v.normal_v = SCENE_TEXEL_F(scene_vertex_texels, 2u * i + 1u);
    return v;
}
uvec4 scene_triangle(uint prim) { return SCENE_TEXEL(scene_triangle_texels, prim); }
ShapeGpu scene_shape(uint i) {
    uvec4 a = SCENE_TEXEL(scene_shape_texels, 2u * i);
    ShapeGpu s;
    s.material = a.x;
    s.flags = a.y;
    s.light_offset = a.z;
    s.first_triangle = a.w;
    s.emission = SCENE_TEXEL_F(scene_shape_texels, 2u * i + 1u);
    return s;
}
TextureGpu scene_texture(uint i) {
    uvec4 a = SCENE_TEXEL(scene_texture_texels, 4u * i);
    TextureGpu t;
    t.offset = a.x;
    t.width = a.y;
    t.height = a.z;
    t.kind = a.w;
    t.color0 = SCENE_TEXEL_F(scene_texture_texels, 4u * i + 1u);
    t.color1 = SCENE_TEXEL_F(scene_texture_texels, 4u * i + 2u);
    t.uv_scale = SCENE_TEXEL_F(scene_texture_texels, 4u * i + 3u);
    return t;
}
vec4 scene_texel(uint i) { return SCENE_TEXEL_F(scene_texel_texels, i); }
LightGpu scene_light(uint i) {
    uvec4 a = SCENE_TEXEL(scene_light_texels, 4u * i);
    LightGpu l;
    l.type = a.x;
    l.index = a.y;
    l.pmf = uintBitsToFloat(a.z);
    l.flags = a.w;
    l.p0 = SCENE_TEXEL_F(scene_light_texels, 4u * i + 1u);
    l.p1 = SCENE_TEXEL_F(scene_light_texels, 4u * i + 2u);
    l.p2 = SCENE_TEXEL_F(scene_light_texels, 4u * i + 3u);
    return l;
}
layout(std430) readonly buffer SceneLightCdf { float scene_light_cdf[]; };  // inclusive prefix
layout(std430) readonly buffer SceneInfoBuffer { SceneInfo scene_info; };
// Per shape, 3 rows of the affine map from a world position on the shape at this frame to
// the same surface point at the previous frame (shapes moving along a keyframe path; the
// identity for static shapes). Only motion vectors and temporal reuse need it.
layout(std430) readonly buffer SceneShapeMotion { vec4 scene_shape_motion[]; };

// Which frame's vertices surface points are evaluated in: 0 this one, else
// scene_info.previous_geometry.x (set through shading.glsl's scene_select_frame).
uint scene_vertex_base = 0u;
// The time surface points are evaluated at, as a fraction of the shutter (0 = open): shapes
// that move over the shutter move linearly between their open and close vertices, as the BVH
// intersects them (bvh.glsl bvh_time). Set with shading.glsl's scene_set_time.
float scene_time = 0.0;

// Vertex i of the selected frame at scene_time.
VertexGpu scene_vertex(uint i) {
    VertexGpu v = scene_vertex_record(scene_vertex_base + i);
#ifdef LOOM_SHAPE_MOTION_BLUR  // only while shapes move over the shutter (bvh.glsl)
    if (scene_time != 0.0) {
        uint close = scene_info.motion.x;
        if (close != 0u) {  // a + t (b - a): static vertices stay exact
            VertexGpu c = scene_vertex_record(scene_vertex_base + close + i);
            v.position_u.xyz += scene_time * (c.position_u.xyz - v.position_u.xyz);
            v.normal_v.xyz += scene_time * (c.normal_v.xyz - v.normal_v.xyz);
        }
    }
#endif
    return v;
}

// Where the surface point p of `shape` was on the previous frame (rigid shape motion).
vec3 previous_position(uint shape, vec3 p) {
    vec4 h = vec4(p, 1.0);
    return vec3(dot(scene_shape_motion[3u * shape], h), dot(scene_shape_motion[3u * shape + 1u], h),
                dot(scene_shape_motion[3u * shape + 2u], h));
}

// The bilinear cell of a bitmap texture at uv (wrap-around; uv origin at the top-left texel
// row 0): the four texels' indices and the weights between them. Within a cell the lookup is
// smooth; its derivative jumps across cells.
struct TextureCell {
    uvec4 texel;  // t00, t10, t01, t11 (scene_texel indices)
    vec2 w;       // bilinear weights
    ivec2 cell;   // which cell
};

TextureCell texture_cell(TextureGpu t, vec2 uv) {
    vec2 st = fract(uv) * vec2(t.width, t.height) - 0.5;
    TextureCell c;
    ivec2 i0 = ivec2(floor(st));
    c.w = st - vec2(i0);
    ivec2 size = ivec2(t.width, t.height);
    ivec2 a = (i0 % size + size) % size, b = (a + 1) % size;
    c.texel = t.offset + uvec4(a.y * size.x + a.x, a.y * size.x + b.x, b.y * size.x + a.x,
                               b.y * size.x + b.x);
    c.cell = a;
    return c;
}

// Bilinear texture lookup with wrap-around (uv origin at the top-left texel row 0).
vec4 texture_fetch(uint tex, vec2 uv) {
    TextureGpu t = scene_texture(tex);
    uv *= t.uv_scale.xy;
    if (t.kind == 2u) return t.color0;
    if (t.kind == 1u) {
        // Mitsuba checkerboard: alternate in each half of the unit square.
        vec2 f = fract(uv);
        return ((f.x < 0.5) == (f.y < 0.5)) ? t.color0 : t.color1;
    }
    TextureCell c = texture_cell(t, uv);
    vec4 t00 = scene_texel(c.texel.x), t10 = scene_texel(c.texel.y);
    vec4 t01 = scene_texel(c.texel.z), t11 = scene_texel(c.texel.w);
    return mix(mix(t00, t10, c.w.x), mix(t01, t11, c.w.x), c.w.y);
}

// texture_fetch with its partial derivatives along texture u and v (within the bilinear cell;
// constant and checkerboard textures have none). Manifold walks differentiate normal maps.
vec4 texture_fetch_grad(uint tex, vec2 uv, out vec4 d_du, out vec4 d_dv) {
    d_du = vec4(0.0);
    d_dv = vec4(0.0);
    TextureGpu t = scene_texture(tex);
    if (t.kind == 1u || t.kind == 2u) return texture_fetch(tex, uv);
    TextureCell c = texture_cell(t, uv * t.uv_scale.xy);
    vec4 t00 = scene_texel(c.texel.x), t10 = scene_texel(c.texel.y);
    vec4 t01 = scene_texel(c.texel.z), t11 = scene_texel(c.texel.w);
    vec2 scale = vec2(t.width, t.height) * t.uv_scale.xy;  // d st / d uv
    d_du = mix(t10 - t00, t11 - t01, c.w.y) * scale.x;
    d_dv = mix(t01 - t00, t11 - t10, c.w.x) * scale.y;
    return mix(mix(t00, t10, c.w.x), mix(t01, t11, c.w.x), c.w.y);
}

// Which bilinear cell texture_fetch reads at uv (ivec2(0) for procedural textures): finite
// differences of a lookup are only valid within one cell.
ivec2 texture_cell_at(uint tex, vec2 uv) {
    TextureGpu t = scene_texture(tex);
    if (t.kind == 1u || t.kind == 2u) return ivec2(0);
    return texture_cell(t, uv * t.uv_scale.xy).cell;
}

// A point on a triangle with its first-order differential geometry. The partials are with
// respect to the barycentrics (u, v) = Hit.bary, p = (1 - u - v) p0 + u p1 + v p2, which
// parameterise every triangle (texture UVs may be missing or degenerate), as manifold walks
// (specular manifold sampling, MNEE) step in them; chain with d(u, v)/d(uv) for texture space.
struct SurfacePoint {
    vec3 p;
    vec3 ng;       // geometric normal (unnormalised winding order, normalised)
    vec3 ns;       // shading normal (interpolated; = ng without vertex normals)
    vec3 tangent;  // dp/d(texture u) from UVs (or an arbitrary tangent): the shading frame's
    vec3 dp_du;    // = p1 - p0
    vec3 dp_dv;    // = p2 - p0
    vec3 dn_du;    // partials of ns: (I - ns ns^T) (n1 - n0) / |n|, n the unnormalised
    vec3 dn_dv;    // interpolated normal; 0 without vertex normals (ns = ng is constant)
    vec2 uv;
    uint shape;
    uint prim;
    float area;    // triangle area
};

void triangle_positions(uint prim, out vec3 p0, out vec3 p1, out vec3 p2) {
    uvec4 tri = scene_triangle(prim);
    p0 = scene_vertex(tri.x).position_u.xyz;
    p1 = scene_vertex(tri.y).position_u.xyz;
    p2 = scene_vertex(tri.z).position_u.xyz;
}

void triangle_uvs(uint prim, out vec2 uv0, out vec2 uv1, out vec2 uv2) {
    uvec4 tri = scene_triangle(prim);
    VertexGpu v0 = scene_vertex(tri.x), v1 = scene_vertex(tri.y), v2 = scene_vertex(tri.z);
    uv0 = vec2(v0.position_u.w, v0.normal_v.w);
    uv1 = vec2(v1.position_u.w, v1.normal_v.w);
    uv2 = vec2(v2.position_u.w, v2.normal_v.w);
}

// Barycentrics (u, v) of the point of triangle prim's plane nearest to p (least squares; p on
// the triangle gives the Hit.bary convention back). Degenerate triangles: the centroid.
vec2 triangle_barycentrics(uint prim, vec3 p) {
    vec3 a, b, c;
    triangle_positions(prim, a, b, c);
    vec3 e1 = b - a, e2 = c - a, v = p - a;
    float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    float dv1 = dot(v, e1), dv2 = dot(v, e2);
    float det = d11 * d22 - d12 * d12;
    if (det == 0.0) return vec2(1.0 / 3.0);
    return vec2(d22 * dv1 - d12 * dv2, d11 * dv2 - d12 * dv1) / det;
}

SurfacePoint surface_point(uint prim, vec2 bary) {
    uvec4 tri = scene_triangle(prim);
    VertexGpu v0 = scene_vertex(tri.x), v1 = scene_vertex(tri.y), v2 = scene_vertex(tri.z);
    float b0 = 1.0 - bary.x - bary.y;
    SurfacePoint s;
    s.prim = prim;
    s.shape = tri.w;
    s.p = b0 * v0.position_u.xyz + bary.x * v1.position_u.xyz + bary.y * v2.position_u.xyz;
    vec3 e1 = v1.position_u.xyz - v0.position_u.xyz, e2 = v2.position_u.xyz - v0.position_u.xyz;
    vec3 c = cross(e1, e2);
    s.area = 0.5 * length(c);
    s.ng = normalize(c);
    vec2 uv0 = vec2(v0.position_u.w, v0.normal_v.w), uv1 = vec2(v1.position_u.w, v1.normal_v.w),
         uv2 = vec2(v2.position_u.w, v2.normal_v.w);
    s.uv = b0 * uv0 + bary.x * uv1 + bary.y * uv2;
    vec3 n = b0 * v0.normal_v.xyz + bary.x * v1.normal_v.xyz + bary.y * v2.normal_v.xyz;
    s.ns = dot(n, n) > 0.0 ? normalize(n) : s.ng;
    s.dp_du = e1;
    s.dp_dv = e2;
    // d(n / |n|) = (I - ns ns^T) dn / |n|: the normalization removes the change along ns.
    float n_len = length(n);
    vec3 dn1 = v1.normal_v.xyz - v0.normal_v.xyz, dn2 = v2.normal_v.xyz - v0.normal_v.xyz;
    s.dn_du = dot(n, n) > 0.0 ? (dn1 - s.ns * dot(s.ns, dn1)) / n_len : vec3(0.0);
    s.dn_dv = dot(n, n) > 0.0 ? (dn2 - s.ns * dot(s.ns, dn2)) / n_len : vec3(0.0);
    // Keep the geometric normal on the side of the shading normal (consistent orientation).
    if (dot(s.ng, s.ns) < 0.0) s.ng = -s.ng;
    // Tangent from the UV parameterisation (pbrt-v4 Triangle::InteractionFromIntersection).
    vec2 duv1 = uv1 - uv0, duv2 = uv2 - uv0;
    float det = duv1.x * duv2.y - duv1.y * duv2.x;
    if (abs(det) > 1e-12) {
        s.tangent = (duv2.y * e1 - duv1.y * e2) / det;
    } else {
        vec3 t, b;
        orthonormal_basis(s.ns, t, b);
        s.tangent = t;
    }
    return s;
}

#endif
