// Ray queries against the triangle BVH built by core/scene/Bvh.cpp: closest hit, any hit
// (shadow rays), 8-bit ray masks. Compressed 8-wide BVH traversal after Ylitie, Karras and
// Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs":
// node groups on a stack, octant-ordered child slots (nearest child first), triangles of a
// node tested right after it. Hits with t in (tmin, tmax] are reported; callers offset ray
// origins themselves (no self-intersection tricks here).
//
// Cost model on lavapipe (Mesa llvmpipe, 8 lanes per SIMD batch): a load with divergent
// addresses is a per-lane loop (~35 ns per instruction whatever its width up to 32 bytes),
// dynamically indexed local arrays are scatter/gather loops, ALU is ~0.4 ns per operation.
// Hence 32-byte loads (u64vec4), a stack held in registers, and few ALU ops per child.
// Define BVH_NO_INT64 on devices without shaderInt64 (16-byte loads, same results).
#ifndef LOOM_BVH_GLSL
#define LOOM_BVH_GLSL

#ifdef EXP_IMAGES
layout(rgba32ui) uniform readonly uimage2D bvh_node_tex;
layout(rgba32ui) uniform readonly uimage2D bvh_tri_tex;
#define BVH_TEXEL(img, i) imageLoad(img, ivec2(int((i) & 8191u), int((i) >> 13u)))
#define BVH_NO_INT64
#endif
#ifndef BVH_NO_INT64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// Node = 3 x 32 bytes, triangle = 2 x 32 bytes: see BvhNode / BvhTriangle in Bvh.h.
layout(std430) readonly buffer BvhNodes { u64vec4 data[]; } bvh_nodes;
layout(std430) readonly buffer BvhTris { u64vec4 data[]; } bvh_tris;
#define BVH_SPLIT(v) uvec4(unpack32((v).x), unpack32((v).y))
#define BVH_SPLIT_HI(v) uvec4(unpack32((v).z), unpack32((v).w))
#else
layout(std430) readonly buffer BvhNodes { uvec4 data[]; } bvh_nodes;
layout(std430) readonly buffer BvhTris { uvec4 data[]; } bvh_tris;
#endif

#ifdef BVH_ADJACENCY
// Opt-in (define BVH_ADJACENCY before the include): a declared but unused buffer would still
// be reflected and has to be bound. Per input triangle: the neighbour across edge (v0,v1),
// (v1,v2), (v2,v0), -1 on a boundary.
layout(std430) readonly buffer BvhAdjacency { ivec4 data[]; } bvh_adjacency;
ivec3 bvh_adjacent(uint prim) { return bvh_adjacency.data[prim].xyz; }
#endif

#define BVH_MASK_ALL 0xffu
// Stack: the top 8 entries live in registers; deeper ones (rare) spill to a local array.
// One entry per tree level at most, and the builder bounds the depth (kBvhMaxDepth = 32).
#define BVH_STACK_SIZE 32

struct Hit {
    float t;
    uint prim;  // index of the triangle in the list given to buildBvh
    vec2 bary;  // (u, v): position = (1 - u - v) * v0 + u * v1 + v * v2
};

// Möller–Trumbore in the unnormalised form Embree uses (edge tests before the division), so
// that shared edges resolve like rtcIntersect1 as far as float allows.
bool bvh_intersect_triangle(uint index, vec3 o, vec3 d, float tmin, float tmax, uint mask,
                            inout Hit hit) {
#ifdef EXP_TRI_SMALL
    index &= 0x3fffu;
#endif
#ifndef BVH_NO_INT64
    u64vec4 a = bvh_tris.data[2u * index], b = bvh_tris.data[2u * index + 1u];
    uvec4 r0 = BVH_SPLIT(a), r1 = BVH_SPLIT_HI(a), r2 = BVH_SPLIT(b), r3 = BVH_SPLIT_HI(b);
#elif defined(EXP_IMAGES)
    uvec4 r0 = BVH_TEXEL(bvh_tri_tex, 4u * index), r1 = BVH_TEXEL(bvh_tri_tex, 4u * index + 1u);
    uvec4 r2 = BVH_TEXEL(bvh_tri_tex, 4u * index + 2u), r3 = BVH_TEXEL(bvh_tri_tex, 4u * index + 3u);
#else
    uvec4 r0 = bvh_tris.data[4u * index], r1 = bvh_tris.data[4u * index + 1u];
    uvec4 r2 = bvh_tris.data[4u * index + 2u], r3 = bvh_tris.data[4u * index + 3u];
#endif
    vec3 e1 = uintBitsToFloat(r1.xyz), e2 = uintBitsToFloat(r2.xyz), ng = uintBitsToFloat(r3.xyz);
    vec3 c = uintBitsToFloat(r0.xyz) - o;
    vec3 r = cross(c, d);
    float den = dot(ng, d);
    float sgn = den < 0.0 ? -1.0 : 1.0;
    float area = abs(den);
    float u = dot(e2, r) * sgn;
    float v = -dot(e1, r) * sgn;
    float t = dot(c, ng) * sgn;
    bool ok = den != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= area && t > area * tmin &&
              t <= area * tmax && (r1.w & mask) != 0u;
    if (ok) {
        float inv = 1.0 / area;
        hit.t = t * inv;
        hit.prim = r0.w;
        hit.bary = vec2(u, v) * inv;
    }
    return ok;
}

// Permutes the 8 bits of x so that bit s moves to bit s ^ f (f < 8).
uint bvh_xor_permute(uint x, uint f) {
    if ((f & 1u) != 0u) x = ((x & 0x55u) << 1u) | ((x >> 1u) & 0x55u);
    if ((f & 2u) != 0u) x = ((x & 0x33u) << 2u) | ((x >> 2u) & 0x33u);
    if ((f & 4u) != 0u) x = ((x & 0x0fu) << 4u) | ((x >> 4u) & 0x0fu);
    return x;
}

// Bit i of each byte of (words & mask) being nonzero, as 4 bits.
uint bvh_mask_pass(uint words, uint mask4) {
    uint x = words & mask4;
    x = (((x & 0x7f7f7f7fu) + 0x7f7f7f7fu) | x) & 0x80808080u;
    return ((x >> 7u) | (x >> 14u) | (x >> 21u) | (x >> 28u)) & 0xfu;
}

bool bvh_traverse(vec3 o, vec3 d, float tmin, float tmax, uint mask, const bool any_hit,
                  out Hit hit) {
    hit.t = tmax;
    hit.prim = 0xffffffffu;
    hit.bary = vec2(0.0);
    bool found = false;

    // Per-ray constants: safe reciprocal, octant (sign bit set = negative direction).
    vec3 idir = 1.0 / max(abs(d), vec3(1e-20));
    bvec3 neg = lessThan(d, vec3(0.0));
    idir = mix(idir, -idir, neg);
    vec3 oidir = o * idir;
    // Inner slots are visited in order slot ^ oct_inv descending, i.e. slot == octant first.
    uint oct_inv = 7u - (uint(neg.x) | uint(neg.y) << 1 | uint(neg.z) << 2);
    uint mask4 = (mask & 0xffu) * 0x01010101u;
    // Far planes are scaled by 1 + 2 gamma(3) and then some for the quantised decode, so the
    // slab test is conservative (Ize 2013, "Robust BVH Ray Traversal").
    const float robust = 1.0000008;

    uvec2 s0 = uvec2(0u), s1 = s0, s2 = s0, s3 = s0, s4 = s0, s5 = s0, s6 = s0, s7 = s0;
    uvec2 spill[BVH_STACK_SIZE - 8];
    uint sp = 0u;
    // Node group: x = first inner child, y = octant-ordered hit bits (24..31) | imask (0..7).
    uvec2 ngroup = uvec2(0u, 0x80000000u);
#ifdef EXP_STATS
    uint st_nodes = 0u, st_tris = 0u;
#endif
    while (true) {
#ifdef EXP_STATS
        st_nodes++;
#endif
        // Next child of the group, nearest first.
        uint bit = uint(findMSB(ngroup.y));
        uint slot = (bit - 24u) ^ oct_inv;
        uint node = ngroup.x + uint(bitCount(ngroup.y & ((1u << slot) - 1u) & 0xffu));
        ngroup.y &= ~(1u << bit);
        if (ngroup.y > 0x00ffffffu) {  // push the rest of the group
#ifndef EXP_NO_SPILL
            if (sp >= 8u) spill[sp - 8u] = s7;
#endif
            s7 = s6, s6 = s5, s5 = s4, s4 = s3, s3 = s2, s2 = s1, s1 = s0, s0 = ngroup;
            sp++;
        }

#ifndef BVH_NO_INT64
        u64vec4 na = bvh_nodes.data[3u * node], nb = bvh_nodes.data[3u * node + 1u];
        u64vec4 nc = bvh_nodes.data[3u * node + 2u];
        uvec4 w0 = BVH_SPLIT(na), w1 = BVH_SPLIT_HI(na), w2 = BVH_SPLIT(nb);
        uvec4 w3 = BVH_SPLIT_HI(nb), w4 = BVH_SPLIT(nc), w5 = BVH_SPLIT_HI(nc);
#elif defined(EXP_IMAGES)
        uvec4 w0 = BVH_TEXEL(bvh_node_tex, 6u * node), w1 = BVH_TEXEL(bvh_node_tex, 6u * node + 1u);
        uvec4 w2 = BVH_TEXEL(bvh_node_tex, 6u * node + 2u), w3 = BVH_TEXEL(bvh_node_tex, 6u * node + 3u);
        uvec4 w4 = BVH_TEXEL(bvh_node_tex, 6u * node + 4u), w5 = BVH_TEXEL(bvh_node_tex, 6u * node + 5u);
#else
        uvec4 w0 = bvh_nodes.data[6u * node], w1 = bvh_nodes.data[6u * node + 1u];
        uvec4 w2 = bvh_nodes.data[6u * node + 2u], w3 = bvh_nodes.data[6u * node + 3u];
        uvec4 w4 = bvh_nodes.data[6u * node + 4u], w5 = bvh_nodes.data[6u * node + 5u];
#endif

        // Child planes as ray distances: t = q * scale + base; near planes are the low ones
        // for a positive direction.
        vec3 scale = uintBitsToFloat(((w0.www >> uvec3(0u, 8u, 16u)) & 0xffu) << 23u) * idir;
        vec3 base = uintBitsToFloat(w0.xyz) * idir - oidir;
        vec3 scale_far = scale * robust, base_far = base * robust;
        uvec2 nx = neg.x ? w2.zw : w2.xy, fx = neg.x ? w2.xy : w2.zw;
        uvec2 ny = neg.y ? w3.zw : w3.xy, fy = neg.y ? w3.xy : w3.zw;
        uvec2 nz = neg.z ? w4.zw : w4.xy, fz = neg.z ? w4.xy : w4.zw;
        float t_limit = found ? hit.t : tmax;
        uint hits = 0u;
        for (uint i = 0u; i < 8u; ++i) {
            uint w = i >> 2u, sh = (i & 3u) * 8u;
#ifdef EXP_UCVT
            vec3 tn = vec3((uvec3(nx[w], ny[w], nz[w]) >> sh) & 0xffu) * scale + base;
            vec3 tf = vec3((uvec3(fx[w], fy[w], fz[w]) >> sh) & 0xffu) * scale_far + base_far;
#else
            // Signed conversion: one instruction on x86 (unsigned needs a sequence).
            vec3 tn = vec3(ivec3((uvec3(nx[w], ny[w], nz[w]) >> sh) & 0xffu)) * scale + base;
            vec3 tf = vec3(ivec3((uvec3(fx[w], fy[w], fz[w]) >> sh) & 0xffu)) * scale_far + base_far;
#endif
            float t0 = max(max(tn.x, tn.y), max(tn.z, tmin));
            float t1 = min(min(tf.x, tf.y), min(tf.z, t_limit));
            hits |= t0 <= t1 ? 1u << i : 0u;
        }
#ifndef EXP_NO_MASKPASS
        hits &= bvh_mask_pass(w5.x, mask4) | (bvh_mask_pass(w5.y, mask4) << 4u);
#endif
#ifdef EXP_DOUBLE_ALU
        {
            vec3 scale2 = scale * uintBitsToFloat(floatBitsToUint(1.0) + (sp >> 30u));
            uint hits2 = 0u;
            for (uint i = 0u; i < 8u; ++i) {
                uint w = i >> 2u, sh = (i & 3u) * 8u;
                vec3 tn = vec3(ivec3((uvec3(nx[w], ny[w], nz[w]) >> sh) & 0xffu)) * scale2 + base;
                vec3 tf = vec3(ivec3((uvec3(fx[w], fy[w], fz[w]) >> sh) & 0xffu)) * scale_far + base_far;
                float t0 = max(max(tn.x, tn.y), max(tn.z, tmin));
                float t1 = min(min(tf.x, tf.y), min(tf.z, t_limit));
                hits2 |= t0 <= t1 ? 1u << i : 0u;
            }
            hits |= hits2 & (sp >> 30u);
        }
#endif

        // Leaf slots own 3 triangle bits each: spread the 8 hit bits to 24, keep real ones.
        uint spread = (hits | (hits << 8u)) & 0x00f00fu;
        spread = (spread | (spread << 4u)) & 0x0c30c3u;
        spread = (spread | (spread << 2u)) & 0x249249u;
        uint leaf_mask = w1.z;
        uint tri_hits = (spread * 7u) & leaf_mask;
        uint tri_base = w1.y;
        while (tri_hits != 0u) {
            uint k = uint(findLSB(tri_hits));
            tri_hits &= tri_hits - 1u;
#ifdef EXP_STATS
            st_tris++;
#endif
            uint index = tri_base + uint(bitCount(leaf_mask & ((1u << k) - 1u)));
#ifdef EXP_NO_TRI
            if (index == 0xffffffffu) {
#else
            if (bvh_intersect_triangle(index, o, d, tmin, found ? hit.t : tmax, mask, hit)) {
#endif
                found = true;
                if (any_hit) return true;
            }
        }

        uint imask = w0.w >> 24u;
#ifdef EXP_NO_PERMUTE
        ngroup = uvec2(w1.x, ((hits & imask) << 24u) | imask);
#else
        ngroup = uvec2(w1.x, (bvh_xor_permute(hits & imask, oct_inv) << 24u) | imask);
#endif
        if (ngroup.y <= 0x00ffffffu) {  // no inner child hit: pop
            if (sp == 0u) break;
            ngroup = s0;
            s0 = s1, s1 = s2, s2 = s3, s3 = s4, s4 = s5, s5 = s6, s6 = s7;
            sp--;
#ifndef EXP_NO_SPILL
            if (sp >= 8u) s7 = spill[sp - 8u];
#endif
        }
    }
#ifdef EXP_STATS
    hit.bary = uintBitsToFloat(uvec2(st_nodes, st_tris));
#endif
    return found;
}

bool trace_closest(vec3 o, vec3 d, float tmin, float tmax, uint mask, out Hit hit) {
    return bvh_traverse(o, d, tmin, tmax, mask, false, hit);
}

bool trace_any(vec3 o, vec3 d, float tmin, float tmax, uint mask) {
    Hit hit;
    return bvh_traverse(o, d, tmin, tmax, mask, true, hit);
}

#endif
