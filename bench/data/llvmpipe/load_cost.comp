#version 460
// bench/llvmpipe_loads.sh: what a load costs on the device. Each invocation runs `steps`
// dependent loads at hashed indices below `count` (capped at the data's length) from the
// scene's BVH triangle records (a storage buffer of 64-byte records; the first 32 bytes are
// read) or its BVH node image, one form per kernel (FORM, a define): 0 nothing (the loop and
// hash alone), 1 one float, 2 one vec4, 3 a struct's two vec4 members (a struct load compiles
// to one load per member), 4 the same 32 bytes as one u64vec4, 5 the same 32 bytes as eight
// floats, 6 a vec4 at an address every invocation shares, 7 an RGBA32UI image texel.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D colorImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    int steps;
    int count;
} pc;
#ifndef FORM
#define FORM 0
#endif

#if FORM == 4
layout(std430) readonly buffer BvhTris { u64vec4 d[]; } bvh_tris;
#define RECORDS (uint(bvh_tris.d.length()) / 2u)
#elif FORM == 3
struct Record { vec4 a, b, c, e; };
layout(std430) readonly buffer BvhTris { Record d[]; } bvh_tris;
#define RECORDS uint(bvh_tris.d.length())
#elif FORM == 2 || FORM == 6
layout(std430) readonly buffer BvhTris { vec4 d[]; } bvh_tris;
#define RECORDS (uint(bvh_tris.d.length()) / 4u)
#elif FORM == 7
layout(rgba32ui) uniform readonly uimage2D bvh_nodes;
#define RECORDS uint(imageSize(bvh_nodes).x * imageSize(bvh_nodes).y)
#else
layout(std430) readonly buffer BvhTris { float d[]; } bvh_tris;
#define RECORDS (uint(bvh_tris.d.length()) / 16u)
#endif

vec4 load(uint i) {
#if FORM == 0
    return vec4(float(i));
#elif FORM == 1
    return vec4(bvh_tris.d[16u * i]);
#elif FORM == 2
    return bvh_tris.d[4u * i];
#elif FORM == 3
    Record r = bvh_tris.d[i];
    return r.a + r.b;
#elif FORM == 4
    u64vec4 v = bvh_tris.d[2u * i];
    return uintBitsToFloat(uvec4(unpack32(v.x), unpack32(v.y))) +
           uintBitsToFloat(uvec4(unpack32(v.z), unpack32(v.w)));
#elif FORM == 5
    uint b = 16u * i;
    return vec4(bvh_tris.d[b], bvh_tris.d[b + 1u], bvh_tris.d[b + 2u], bvh_tris.d[b + 3u]) +
           vec4(bvh_tris.d[b + 4u], bvh_tris.d[b + 5u], bvh_tris.d[b + 6u], bvh_tris.d[b + 7u]);
#elif FORM == 6
    return bvh_tris.d[0];
#elif FORM == 7
    return uintBitsToFloat(imageLoad(bvh_nodes, ivec2(int(i & 8191u), int(i >> 13u))));
#endif
}

uint hash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    uint n = max(min(uint(pc.count), RECORDS), 1u);
    uint idx = hash(uint(p.x) + 4096u * uint(p.y) + pc.frameIndex);
    vec4 acc = vec4(0.0);
    for (int s = 0; s < pc.steps; ++s) {
        acc += load(idx % n);
        idx = hash(idx ^ floatBitsToUint(acc.x));  // the next address depends on this load
    }
    imageStore(colorImage, p, acc);
}
