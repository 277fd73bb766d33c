// Ray queries against the triangle BVH built by core/scene/Bvh.cpp: closest hit, any hit
// (shadow rays), 8-bit ray masks. Compressed 8-wide BVH traversal after Ylitie, Karras and
// Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs":
// node groups on a stack, octant-ordered child slots (nearest child first), the triangles of
// a node tested right after it. Hits with t in (tmin, tmax] are reported; callers offset ray
// origins themselves (no self-intersection tricks here).
//
// Cost model on lavapipe (llvmpipe, SIMD batches of 8 invocations), measured: a buffer load
// with divergent addresses is a per-lane loop with a branch per lane and component (~35 ns
// per load instruction, any width up to 32 bytes, nearly as much when few lanes are active);
// an image load is one unrolled, branch-free 16-byte load per lane (cheaper when most lanes
// are active, as in node fetches); a dynamically indexed local array is a scatter/gather
// loop; ALU ~0.4 ns per operation. Hence nodes in an image, triangles as 32-byte buffer loads
// (sparse lanes in the triangle loop), a register stack and few ALU operations per child.
// Define BVH_NO_INT64 for devices without shaderInt64 (16-byte loads, identical results).
#ifndef LOOM_BVH_GLSL
#define LOOM_BVH_GLSL
#ifndef BVH_NO_INT64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif

// Nodes: 5 RGBA32UI texels each, texel i at (i % 8192, i / 8192); see BvhNode in Bvh.h.
layout(rgba32ui) uniform readonly uimage2D bvh_nodes;
#define BVH_NODE_TEXEL(i) imageLoad(bvh_nodes, ivec2(int((i) & 8191u), int((i) >> 13u)))

// Triangles: 64 bytes each (BvhTriangle): v0 + prim, e1 + mask, e2, geometric normal.
#ifndef BVH_NO_INT64
layout(std430) readonly buffer BvhTris { u64vec4 data[]; } bvh_tris;
#else
layout(std430) readonly buffer BvhTris { uvec4 data[]; } bvh_tris;
#endif

// Triangle adjacency for passes that walk meshes, per input triangle (prim): the neighbour
// across edge (v0,v1), (v1,v2), (v2,v0), -1 on a boundary (scene::triangleAdjacency).
layout(std430) readonly buffer BvhAdjacency { ivec4 data[]; } bvh_adjacency;
ivec3 bvh_adjacent(uint prim) { return bvh_adjacency.data[prim].xyz; }

#define BVH_MASK_ALL 0xffu
// Which tree rays traverse: node and triangle-record bases (0: the first tree; a scene with
// moving shapes keeps the previous frame's tree behind it, see shading.glsl scene_select_frame).
uint bvh_node_base = 0u, bvh_tri_base = 0u;
// Motion blur of moving shapes (Bvh.h buildMotionBvh): the ray's time as a fraction of the
// shutter (0 = open, 1 = close), and the distance from a triangle record to its shutter-close
// twin in the selected tree (0: no motion). Set through shading.glsl's scene_set_time and
// scene_select_frame; moving records (bit 8 of the mask word) move linearly between the two.
// The interpolation is compiled in with LOOM_SHAPE_MOTION_BLUR only, which the Renderer defines
// while shapes move over the shutter: even untaken, it slows static traversal by about 13 %
// (bench_bvh, lavapipe: diffuse rays 3.31 -> 2.87 Mrays/s).
float bvh_time = 0.0;
uint bvh_motion_offset = 0u;
// The stack holds one node group per tree level at most; the builder bounds the depth
// (kBvhMaxDepth). The top 8 entries live in registers, deeper ones spill to a local array.
#define BVH_STACK_SIZE 32

// Traversal steps (node and triangle loop iterations together, which bounds each loop's own
// count) this invocation has run, over all its queries. lavapipe (llvmpipe) silently
// stops any loop after 65535 iterations per invocation, summed over every entry into it
// (tests/gpu/test_shader.cpp LoopIterationsPerInvocation), so kernels bound their work per
// dispatch and report this count to catch a truncated traversal (a wrong image, no error).
uint bvh_iterations = 0u;
const uint BVH_LOOP_LIMIT = 65535u;

#ifdef BVH_STATS
#extension GL_KHR_shader_subgroup_arithmetic : require
// Traversal statistics of the last query of this invocation (profiling only): nodes and
// triangles visited, and iterations of the triangle loop its SIMD batch (subgroup) ran.
uint bvh_stat_nodes = 0u, bvh_stat_tris = 0u, bvh_stat_tri_iters = 0u;
#endif

struct Hit {
    float t;
    uint prim;  // index of the triangle in the list given to buildBvh
    vec2 bary;  // (u, v): position = (1 - u - v) * v0 + u * v1 + v * v2
};

// Möller–Trumbore in the unnormalised form Embree uses (edge tests before the division), so
// that shared edges resolve like rtcIntersect1 as far as float allows.
bool bvh_intersect_plane(vec3 v0, vec3 e1, vec3 e2, vec3 ng, uint prim, uint mask_word, vec3 o,
                         vec3 d, float tmin, float tmax, uint mask, inout Hit hit) {
    vec3 c = v0 - o;
    vec3 r = cross(c, d);
    float den = dot(ng, d);
    float sgn = den < 0.0 ? -1.0 : 1.0;
    float area = abs(den);
    float u = dot(e2, r) * sgn;
    float v = -dot(e1, r) * sgn;
    float t = dot(c, ng) * sgn;
    bool ok = den != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= area && t > area * tmin &&
              t <= area * tmax && (mask_word & mask) != 0u;
    if (ok) {
        float inv = 1.0 / area;
        hit.t = t * inv;
        hit.prim = prim;
        hit.bary = vec2(u, v) * inv;
    }
    return ok;
}

// Record `index` as vec4s (xyz, w bits): v0 | prim, e1 | mask word, e2, ng.
void bvh_load_triangle(uint index, out uvec4 r0, out uvec4 r1, out uvec4 r2, out uvec4 r3) {
#ifndef BVH_NO_INT64
    u64vec4 a = bvh_tris.data[2u * index], b = bvh_tris.data[2u * index + 1u];
    r0 = uvec4(unpack32(a.x), unpack32(a.y));
    r1 = uvec4(unpack32(a.z), unpack32(a.w));
    r2 = uvec4(unpack32(b.x), unpack32(b.y));
    r3 = uvec4(unpack32(b.z), unpack32(b.w));
#else
    r0 = bvh_tris.data[4u * index];
    r1 = bvh_tris.data[4u * index + 1u];
    r2 = bvh_tris.data[4u * index + 2u];
    r3 = bvh_tris.data[4u * index + 3u];
#endif
}

// A moving triangle at bvh_time: vertices on the segments from its record to its shutter-close
// twin, in the form a + t (b - a) that scene.glsl's surface points use (exact at t = 0).
// Apart from the static test, so that static scenes keep that test's code and registers.
// r0..r2: the record's words, already loaded.
bool bvh_intersect_moving(uint index, uvec4 r0, uvec4 r1, uvec4 r2, vec3 o, vec3 d, float tmin,
                          float tmax, uint mask, inout Hit hit) {
    uvec4 m0, m1, m2, m3;
    bvh_load_triangle(index + bvh_motion_offset, m0, m1, m2, m3);
    vec3 v0 = uintBitsToFloat(r0.xyz), c0 = uintBitsToFloat(m0.xyz);
    vec3 p1 = v0 + uintBitsToFloat(r1.xyz), p2 = v0 + uintBitsToFloat(r2.xyz);
    vec3 q0 = v0 + bvh_time * (c0 - v0);
    vec3 q1 = p1 + bvh_time * (c0 + uintBitsToFloat(m1.xyz) - p1);
    vec3 q2 = p2 + bvh_time * (c0 + uintBitsToFloat(m2.xyz) - p2);
    vec3 e1 = q1 - q0, e2 = q2 - q0;
    return bvh_intersect_plane(q0, e1, e2, cross(e1, e2), r0.w, r1.w, o, d, tmin, tmax, mask,
                               hit);
}

bool bvh_intersect_triangle(uint index, vec3 o, vec3 d, float tmin, float tmax, uint mask,
                            inout Hit hit) {
    uvec4 r0, r1, r2, r3;
    bvh_load_triangle(index, r0, r1, r2, r3);
#ifdef LOOM_SHAPE_MOTION_BLUR  // only while shapes move over the shutter (Renderer)
    if ((r1.w & 0x100u) != 0u && bvh_time != 0.0)
        return bvh_intersect_moving(index, r0, r1, r2, o, d, tmin, tmax, mask, hit);
#endif
    return bvh_intersect_plane(uintBitsToFloat(r0.xyz), uintBitsToFloat(r1.xyz),
                               uintBitsToFloat(r2.xyz), uintBitsToFloat(r3.xyz), r0.w, r1.w, o, d,
                               tmin, tmax, mask, hit);
}

// Moves bit s of the 8-bit x to bit s ^ f (f < 8).
uint bvh_xor_permute(uint x, uint f) {
    if ((f & 1u) != 0u) x = ((x & 0x55u) << 1u) | ((x >> 1u) & 0x55u);
    if ((f & 2u) != 0u) x = ((x & 0x33u) << 2u) | ((x >> 2u) & 0x33u);
    if ((f & 4u) != 0u) x = ((x & 0x0fu) << 4u) | ((x >> 4u) & 0x0fu);
    return x;
}

#ifndef BVH_MAX_VISITS
#define BVH_MAX_VISITS (1u << 24)
#endif

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
    // Far planes are scaled by 1 + 2 gamma(3) and then some for the quantised decode, so the
    // slab test is conservative (Ize 2013, "Robust BVH Ray Traversal").
    const float robust = 1.0000008;

    uvec2 s0 = uvec2(0u), s1 = s0, s2 = s0, s3 = s0, s4 = s0, s5 = s0, s6 = s0, s7 = s0;
    uvec2 spill[BVH_STACK_SIZE - 8];
    uint sp = 0u;
    // Node group: x = first inner child; y = octant-ordered hit bits (24..31) | offset of each
    // slot's inner child from x (3 bits per slot).
    uvec2 ngroup = uvec2(0u, 0x80000000u);
#ifdef BVH_STATS
    bvh_stat_nodes = 0u, bvh_stat_tris = 0u, bvh_stat_tri_iters = 0u;
#endif
    // A well-formed tree visits each node at most once; the cap only ends the loop on a corrupt
    // node buffer (a cycle), so that no ray runs forever (the GPU watchdog's loop bound).
    for (uint visits = 0u; visits < BVH_MAX_VISITS; ++visits) {
        bvh_iterations++;
#ifdef BVH_STATS
        bvh_stat_nodes++;
#endif
        // Next child of the group, nearest first; push the rest.
        uint bit = uint(findMSB(ngroup.y));
        uint slot = (bit - 24u) ^ oct_inv;
        uint node = ngroup.x + ((ngroup.y >> (slot * 3u)) & 7u);
        ngroup.y &= ~(1u << bit);
        if (ngroup.y > 0x00ffffffu) {
            if (sp >= 8u) spill[sp - 8u] = s7;
            s7 = s6, s6 = s5, s5 = s4, s4 = s3, s3 = s2, s2 = s1, s1 = s0, s0 = ngroup;
            sp++;
        }

        uint texel = 5u * (bvh_node_base + node);
        uvec4 w0 = BVH_NODE_TEXEL(texel), w1 = BVH_NODE_TEXEL(texel + 1u);
        uvec4 w2 = BVH_NODE_TEXEL(texel + 2u), w3 = BVH_NODE_TEXEL(texel + 3u);
        uvec4 w4 = BVH_NODE_TEXEL(texel + 4u);

        // Child planes as ray distances t = q * scale + base; near planes are the low ones
        // for a positive direction.
        vec3 scale = uintBitsToFloat(((w0.www >> uvec3(0u, 8u, 16u)) & 0xffu) << 23u) * idir;
        vec3 base = uintBitsToFloat(w0.xyz) * idir - oidir;
        vec3 scale_far = scale * robust, base_far = base * robust;
        uvec2 nx = neg.x ? w2.zw : w2.xy, fx = neg.x ? w2.xy : w2.zw;
        uvec2 ny = neg.y ? w3.zw : w3.xy, fy = neg.y ? w3.xy : w3.zw;
        uvec2 nz = neg.z ? w4.zw : w4.xy, fz = neg.z ? w4.xy : w4.zw;
        uint hits = 0u;
        for (uint i = 0u; i < 8u; ++i) {
            uint w = i >> 2u, sh = (i & 3u) * 8u;
            // Signed conversion: one instruction on x86, unsigned needs a sequence.
            vec3 tn = vec3(ivec3((uvec3(nx[w], ny[w], nz[w]) >> sh) & 0xffu)) * scale + base;
            vec3 tf = vec3(ivec3((uvec3(fx[w], fy[w], fz[w]) >> sh) & 0xffu)) * scale_far +
                      base_far;
            float t0 = max(max(tn.x, tn.y), max(tn.z, tmin));
            float t1 = min(min(tf.x, tf.y), min(tf.z, hit.t));
            hits |= t0 <= t1 ? 1u << i : 0u;
        }
        if (((w1.z >> 24u) & mask) == 0u) hits = 0u;  // no triangle below matches the mask

        // Leaf slot s owns triangle bits 3s..3s+2: spread the 8 hit bits to 24, keep real ones.
        uint spread = (hits | (hits << 8u)) & 0x00f00fu;
        spread = (spread | (spread << 4u)) & 0x0c30c3u;
        spread = (spread | (spread << 2u)) & 0x249249u;
        uint leaf_bits = w1.z & 0x00ffffffu;
        uint tri_hits = (spread * 7u) & leaf_bits;
#ifdef BVH_STATS
        bvh_stat_tri_iters += subgroupMax(bitCount(tri_hits));
#endif
        while (tri_hits != 0u) {
            uint k = uint(findLSB(tri_hits));
            tri_hits &= tri_hits - 1u;
            bvh_iterations++;
#ifdef BVH_STATS
            bvh_stat_tris++;
#endif
            uint index = bvh_tri_base + w1.y + uint(bitCount(leaf_bits & ((1u << k) - 1u)));
            if (bvh_intersect_triangle(index, o, d, tmin, hit.t, mask, hit)) {
                found = true;
                if (any_hit) return true;
            }
        }

        uint inner_hits = bvh_xor_permute(hits & (w0.w >> 24u), oct_inv);
        ngroup = uvec2(w1.x, (inner_hits << 24u) | w1.w);
        if (ngroup.y <= 0x00ffffffu) {  // no inner child hit: pop
            if (sp == 0u) break;
            ngroup = s0;
            s0 = s1, s1 = s2, s2 = s3, s3 = s4, s4 = s5, s5 = s6, s6 = s7;
            sp--;
            if (sp >= 8u) s7 = spill[sp - 8u];
        }
    }
    return found;
}

// Nearest hit with t in (tmin, tmax] among triangles whose mask shares a bit with `mask`
// (BVH_MASK_ALL: every triangle). On a miss returns false, hit.t = tmax, hit.prim = ~0u.
bool trace_closest(vec3 o, vec3 d, float tmin, float tmax, uint mask, out Hit hit) {
    return bvh_traverse(o, d, tmin, tmax, mask, false, hit);
}

// Whether any such hit exists (shadow rays); stops at the first one found.
bool trace_any(vec3 o, vec3 d, float tmin, float tmax, uint mask) {
    Hit hit;
    return bvh_traverse(o, d, tmin, tmax, mask, true, hit);
}

#endif
