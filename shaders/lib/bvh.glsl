// Ray queries against the triangle BVH built by core/scene/Bvh.cpp: closest hit, any hit
// (shadow rays), 8-bit ray masks. Compressed 8-wide BVH traversal after Ylitie, Karras and
// Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"
// (node groups on a stack, octant-ordered child slots, nearest child first).
// Callers offset ray origins themselves; hits with t in (tmin, tmax] are reported.
#ifndef LOOM_BVH_GLSL
#define LOOM_BVH_GLSL

// Node layout: see BvhNode in core/scene/Bvh.h (5 uvec4 per node).
layout(std430) readonly buffer BvhNodes { uvec4 data[]; } bvh_nodes;
// Triangle records (BvhTriangle, 3 vec4): v0 + prim id, v1 - v0 + mask, v2 - v0.
layout(std430) readonly buffer BvhTris { vec4 data[]; } bvh_tris;
#ifdef BVH_ADJACENCY
// Opt-in (define BVH_ADJACENCY before the include): a declared but unused buffer would still
// be reflected and has to be bound. Per input triangle: the neighbour across edge (v0,v1),
// (v1,v2), (v2,v0), -1 on a boundary.
layout(std430) readonly buffer BvhAdjacency { ivec4 data[]; } bvh_adjacency;
ivec3 bvh_adjacent(uint prim) { return bvh_adjacency.data[prim].xyz; }
#endif

// Depth bound guaranteed by the builder (kBvhMaxDepth): one stack entry per level.
#define BVH_STACK_SIZE 24
#define BVH_MASK_ALL 0xffu

struct Hit {
    float t;
    uint prim;  // index of the triangle in the list given to buildBvh
    vec2 bary;  // (u, v): position = (1 - u - v) * v0 + u * v1 + v * v2
};

// Slab tests are conservative: far distances are scaled by 1 + 2 gamma(3) plus the error of
// the quantised decode (Ize 2013, "Robust BVH Ray Traversal").
const float BVH_ROBUST = 1.0000008;

// Möller–Trumbore in the unnormalised form Embree uses: edge tests before the division, so
// the result matches rtcIntersect1 on shared edges as closely as float allows.
bool bvh_intersect_triangle(uint index, vec3 o, vec3 d, float tmin, inout float tmax,
                            uint mask, inout Hit hit) {
#ifdef EXP_TRI_SMALL
    index &= 0x3fffu;
#endif
#ifdef EXP_TRI_NO_LOADS
    vec4 r0 = vec4(float(index) * 1e-6, 1, 2, uintBitsToFloat(index)), r1 = vec4(o * 0.01, uintBitsToFloat(0xffu)), r2 = vec4(d.yzx, index);
#elif defined(EXP_TRI_LOADS_ONLY)
    vec4 r0 = bvh_tris.data[3u * index];
    vec4 r1 = bvh_tris.data[3u * index + 1u];
    vec4 r2 = bvh_tris.data[3u * index + 2u];
    hit.bary += r0.xy + r1.zw + r2.xw;
    return false;
#else
    vec4 r0 = bvh_tris.data[3u * index];
    vec4 r1 = bvh_tris.data[3u * index + 1u];
    vec4 r2 = bvh_tris.data[3u * index + 2u];
#endif
    vec3 e1 = r1.xyz, e2 = r2.xyz;
    vec3 ng = cross(e1, e2);
    vec3 c = r0.xyz - o;
    vec3 r = cross(c, d);
    float den = dot(ng, d);
    float sgn = den < 0.0 ? -1.0 : 1.0;
    float area = abs(den);
    float u = dot(e2, r) * sgn;
    float v = -dot(e1, r) * sgn;
    float t = dot(c, ng) * sgn;
    bool ok = den != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= area && t > area * tmin &&
              t <= area * tmax && (floatBitsToUint(r1.w) & mask) != 0u;
    if (ok) {
        float inv = 1.0 / area;
        tmax = t * inv;
        hit.t = tmax;
        hit.prim = floatBitsToUint(r0.w);
        hit.bary = vec2(u, v) * inv;
    }
    return ok;
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
    // Inner child slots are visited in order slot ^ oct_inv descending: slot == octant first.
    uint oct_inv = 7u - (uint(neg.x) | uint(neg.y) << 1 | uint(neg.z) << 2);

#ifdef EXP_REGSTACK
    uvec2 r0 = uvec2(0), r1 = r0, r2 = r0, r3 = r0, r4 = r0, r5 = r0, r6 = r0, r7 = r0, r8 = r0, r9 = r0;
#else
    uvec2 stack[BVH_STACK_SIZE];
#endif
    uint sp = 0u;
    // Node group: x = first child node, y = inner-child hit bits (24..31) | imask (0..7).
    uvec2 ngroup = uvec2(0u, 0x80000000u);
#ifdef EXP_STATS
    uint st_nodes = 0u, st_tris = 0u, st_iters = 0u;
#endif
    while (true) {
#ifdef EXP_STATS
        st_nodes++;
#endif
        // Next child of the current group, in octant order.
        uint bit = uint(findMSB(ngroup.y));
        uint slot = (bit - 24u) ^ oct_inv;
        uint node = ngroup.x + uint(bitCount(ngroup.y & ((1u << slot) - 1u) & 0xffu));
        ngroup.y &= ~(1u << bit);
#ifdef EXP_REGSTACK
        if (ngroup.y > 0x00ffffffu) { r9 = r8; r8 = r7; r7 = r6; r6 = r5; r5 = r4; r4 = r3; r3 = r2; r2 = r1; r1 = r0; r0 = ngroup; sp++; }
#else
        if (ngroup.y > 0x00ffffffu) stack[sp++] = ngroup;
#endif

        uvec4 n0 = bvh_nodes.data[5u * node];
        uvec4 n1 = bvh_nodes.data[5u * node + 1u];
        uvec4 n2 = bvh_nodes.data[5u * node + 2u];
        uvec4 n3 = bvh_nodes.data[5u * node + 3u];
        uvec4 n4 = bvh_nodes.data[5u * node + 4u];
#ifdef EXP_DOUBLE_LOAD
        n0 ^= bvh_nodes.data[5u * node + 5u] & uvec4(sp & 0x10000u);
        n1 ^= bvh_nodes.data[5u * node + 6u] & uvec4(sp & 0x10000u);
        n2 ^= bvh_nodes.data[5u * node + 7u] & uvec4(sp & 0x10000u);
        n3 ^= bvh_nodes.data[5u * node + 8u] & uvec4(sp & 0x10000u);
        n4 ^= bvh_nodes.data[5u * node + 9u] & uvec4(sp & 0x10000u);
#endif

        // Decode: plane = origin + q * 2^e, as ray distances t = q * scale + base.
        vec3 scale = uintBitsToFloat(((n0.www >> uvec3(0u, 8u, 16u)) & 0xffu) << 23u) * idir;
        vec3 base = uintBitsToFloat(n0.xyz) * idir - oidir;
        // Near planes are the low ones for a positive direction.
        uvec2 nx = neg.x ? n2.zw : n2.xy, fx = neg.x ? n2.xy : n2.zw;
        uvec2 ny = neg.y ? n3.zw : n3.xy, fy = neg.y ? n3.xy : n3.zw;
        uvec2 nz = neg.z ? n4.zw : n4.xy, fz = neg.z ? n4.xy : n4.zw;
        float t_limit = found ? hit.t : tmax;
        uint hits = 0u;
        for (uint i = 0u; i < 8u; ++i) {
            uint w = i >> 2u, sh = (i & 3u) * 8u;
            vec3 qn = vec3((uvec3(nx[w], ny[w], nz[w]) >> sh) & 0xffu);
            vec3 qf = vec3((uvec3(fx[w], fy[w], fz[w]) >> sh) & 0xffu);
            vec3 tn = qn * scale + base;
            vec3 tf = qf * scale + base;
            float t0 = max(max(tn.x, tn.y), max(tn.z, tmin));
            float t1 = min(min(min(tf.x, tf.y), tf.z) * BVH_ROBUST, t_limit);
            uint meta = (n1[2u + w] >> sh) & 0xffu;
            // Inner children (offset >= 24) go to their octant-ordered bit.
            uint bit_index = (meta & 31u) ^ ((meta & 0x18u) == 0x18u ? oct_inv : 0u);
            if (t0 <= t1) hits |= (meta >> 5u) << bit_index;
        }
        if (((n1.x >> 24u) & mask) == 0u) hits = 0u;  // subtree has no triangle for this mask

        // Triangles of the hit leaf children.
        uint tri_base = n1.y;
        uint tri_hits = hits & 0x00ffffffu;
        while (tri_hits != 0u) {
            uint k = uint(findLSB(tri_hits));
            tri_hits &= tri_hits - 1u;
#ifdef EXP_STATS
            st_tris++;
#endif
            float t_max = found ? hit.t : tmax;
#ifdef EXP_NO_TRI
            if (false) {
#else
            if (bvh_intersect_triangle(tri_base + k, o, d, tmin, t_max, mask, hit)) {
#endif
                found = true;
                if (any_hit) return true;
            }
        }

        ngroup = uvec2(n1.x & 0x00ffffffu, (hits & 0xff000000u) | (n0.w >> 24u));
        if (ngroup.y <= 0x00ffffffu) {
            if (sp == 0u) break;
#ifdef EXP_REGSTACK
            ngroup = r0; r0 = r1; r1 = r2; r2 = r3; r3 = r4; r4 = r5; r5 = r6; r6 = r7; r7 = r8; r8 = r9; --sp;
#else
            ngroup = stack[--sp];
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
