#version 460
// Test kernel: surface_point's partials w.r.t. the barycentrics (dp/du, dp/dv, dn/du, dn/dv)
// next to central differences of its position and shading normal with step h, at `count`
// random points of the scene's triangles. The differences use the step the floats really took
// ((u + h) - (u - h): exact by Sterbenz for u >= 3h, within an ulp below), so only truncation
// and rounding separate them.
#include "lib/rng.glsl"
#include "lib/scene.glsl"

layout(local_size_x = 64) in;
// Per point 12 vec4: (u, v, prim, h), dp/du, dp/dv, dn/du, dn/dv, the four differences, and the
// triangle's vertex normals n0, n1, n2 (for the host's double-precision reference).
layout(std430) writeonly buffer Results { vec4 results[]; };
layout(push_constant) uniform Params {
    uint count;
    uint seed;
    float h;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Rng rng = rng_init(uvec2(i, 0u), 0u, pc.seed);
    uint prim = min(uint(rng_next(rng) * float(scene_info.counts.x)), scene_info.counts.x - 1u);
    vec2 b = rng_next2(rng);
    if (b.x + b.y > 1.0) b = 1.0 - b;
    SurfacePoint s = surface_point(prim, b);

    vec2 up = b + vec2(pc.h, 0.0), um = b - vec2(pc.h, 0.0);
    vec2 vp = b + vec2(0.0, pc.h), vm = b - vec2(0.0, pc.h);
    SurfacePoint su = surface_point(prim, up), sU = surface_point(prim, um);
    SurfacePoint sv = surface_point(prim, vp), sV = surface_point(prim, vm);
    float du = up.x - um.x, dv = vp.y - vm.y;

    uvec4 tri = scene_triangle(prim);
    uint o = 12u * i;
    results[o] = vec4(b, float(prim), pc.h);
    results[o + 1u] = vec4(s.dp_du, 0.0);
    results[o + 2u] = vec4(s.dp_dv, 0.0);
    results[o + 3u] = vec4(s.dn_du, 0.0);
    results[o + 4u] = vec4(s.dn_dv, 0.0);
    results[o + 5u] = vec4((su.p - sU.p) / du, 0.0);
    results[o + 6u] = vec4((sv.p - sV.p) / dv, 0.0);
    results[o + 7u] = vec4((su.ns - sU.ns) / du, 0.0);
    results[o + 8u] = vec4((sv.ns - sV.ns) / dv, 0.0);
    results[o + 9u] = vec4(scene_vertex_record(tri.x).normal_v.xyz, 0.0);
    results[o + 10u] = vec4(scene_vertex_record(tri.y).normal_v.xyz, 0.0);
    results[o + 11u] = vec4(scene_vertex_record(tri.z).normal_v.xyz, 0.0);
}
