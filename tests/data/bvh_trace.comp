#version 460
// Traces a buffer of rays through lib/bvh.glsl (tests/gpu/test_bvh.cpp, bench/bench_bvh.cpp).
// Ray i = (origin, tmin), (direction, tmax); result i = (t, prim, u, v) for closest hit
// (prim = ~0u on a miss) or (occluded, 0, 0, 0) for any hit. With BVH_STATS defined, z and w
// of a closest-hit result are the nodes and triangles visited and x the triangle-loop
// iterations its subgroup ran; a motion tree (Bvh.h buildMotionBvh) is traced at shutter
// fraction `time`; with BVH_ADJACENCY, xyz of result i are the neighbours of
// triangle i instead.
#include "lib/bvh.glsl"

layout(local_size_x = 64) in;
#ifndef BVH_NO_INT64
layout(std430) readonly buffer Rays { u64vec4 data[]; } rays;  // one 32-byte load per ray
#else
layout(std430) readonly buffer Rays { vec4 data[]; } rays;
#endif
layout(std430) writeonly buffer Results { uvec4 data[]; } results;
layout(push_constant) uniform Params {
    uint rayCount;
    uint mask;
    uint anyHit;
    float time;          // shutter fraction of a motion tree (bvh_time)
    uint motionOffset;   // BvhGpu::motionOffset (0: static tree)
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.rayCount) return;
    bvh_time = pc.time;
    bvh_motion_offset = pc.motionOffset;
#ifndef BVH_NO_INT64
    u64vec4 r = rays.data[i];
    vec4 a = uintBitsToFloat(uvec4(unpack32(r.x), unpack32(r.y)));
    vec4 b = uintBitsToFloat(uvec4(unpack32(r.z), unpack32(r.w)));
#else
    vec4 a = rays.data[2u * i], b = rays.data[2u * i + 1u];
#endif
    if (pc.anyHit != 0u) {
        results.data[i] = uvec4(trace_any(a.xyz, b.xyz, a.w, b.w, pc.mask) ? 1u : 0u, 0u, 0u, 0u);
    } else {
        Hit hit;
        bool found = trace_closest(a.xyz, b.xyz, a.w, b.w, pc.mask, hit);
        results.data[i] = found ? uvec4(floatBitsToUint(hit.t), hit.prim,
                                        floatBitsToUint(hit.bary))
                                : uvec4(floatBitsToUint(b.w), 0xffffffffu, 0u, 0u);
#ifdef BVH_STATS
        results.data[i].zw = uvec2(bvh_stat_nodes, bvh_stat_tris);  // instead of (u, v)
        results.data[i].x = bvh_stat_tri_iters;  // instead of t
#endif
    }
#ifdef BVH_ADJACENCY
    results.data[i].xyz = uvec3(bvh_adjacent(i));
#endif
}
