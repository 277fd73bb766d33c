#version 460
// Test kernel (passes/sms/tests/test_sms.cpp): the Jacobian blocks of a chain's constraints
// (manifold_constraint_blocks, what every Newton step and generalized geometric term solve)
// against (Richardson-extrapolated) central differences of the constraints, moving one vertex in its triangle (normal
// re-interpolated) or one end point at a time. Input rows, per column: 0 (x0, constraint),
// 1 (y, end at infinity), 2 (vertex 0 point, triangle), 3 (vertex 1 point, triangle),
// 4 (es, k), 5 (et, from_light), 6 (h, u offset). With MANIFOLD_ROUGH_CASTERS, rough vertices
// scatter about the offset normal of u (vertex i: u shifted by 0.37 i; manifold_rough_offset),
// held in their frame as the vertex moves. Output row 6 i + j: (analytic, difference) of
// column j of row i, j = 0..5 (previous, this, next vertex; each along its two parameters);
// vec4(-1e30) where the differences of a normal-mapped vertex leave its bilinear texel cell
// (the map's derivative jumps there).
#include "lib/bvh.glsl"
#include "lib/manifold/walk.glsl"

layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

vec4 row(int x, int y) { return imageLoad(inputImage, ivec2(x, y)); }
vec2 offset_u;

// The vertex of triangle prim at point p (in its plane): barycentrics from the Gram system of
// the edges, which are surface_point's dp_du, dp_dv.
ManifoldVertex vertex_at(uint prim, vec3 p) {
    SurfacePoint sp = surface_point(prim, vec2(0.0));
    vec3 d = p - sp.p;
    float g11 = dot(sp.dp_du, sp.dp_du), g12 = dot(sp.dp_du, sp.dp_dv), g22 = dot(sp.dp_dv, sp.dp_dv);
    vec2 r = vec2(dot(sp.dp_du, d), dot(sp.dp_dv, d));
    vec2 b = vec2(g22 * r.x - g12 * r.y, g11 * r.y - g12 * r.x) / (g11 * g22 - g12 * g12);
    ManifoldVertex v = manifold_vertex(prim, b);
#ifdef MANIFOLD_ROUGH_CASTERS
    manifold_rough_offset(v, offset_u);
#endif
    return v;
}

// The normal map's bilinear cell at vertex v (ivec2(-1) without a map).
ivec2 normal_map_cell(ManifoldVertex v) {
    uint nmap = material_normal_map(scene_material(scene_shape(v.shape).material));
    if (nmap == MATERIAL_NO_TEXTURE) return ivec2(-1);
    return texture_cell_at(nmap, surface_point(v.prim, triangle_barycentrics(v.prim, v.p)).uv);
}

vec2 constraint_of(uint kind, ManifoldChain c, vec3 x0, vec3 y, uint i) {
    bool valid;
    return manifold_constraint(kind, manifold_chain_prev(c, i, x0), c.v[i],
                               manifold_chain_next(c, i, y), c.frame[i], valid);
}

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= int(pc.frameSize.x)) return;
    uint kind = uint(row(x, 0).w);
    vec3 x0 = row(x, 0).xyz, y = row(x, 1).xyz;
    vec3 es = row(x, 4).xyz, et = row(x, 5).xyz;
    bool from_light = row(x, 5).w != 0.0;
    float h = row(x, 6).x;
    ManifoldChain c;
    c.k = uint(row(x, 4).w);
    c.end_at_infinity = row(x, 1).w != 0.0;
    for (uint i = 0u; i < c.k; ++i) {
        vec4 v = row(x, 2 + int(i));
        offset_u = fract(row(x, 6).yz + 0.37 * float(i));
        c.v[i] = vertex_at(uint(v.w), v.xyz);
    }
    manifold_choose_frames(c, y);
    // One loop over (vertex i, column j, step q, sign), its trip count known only at run time,
    // and each heavy step in a loop of its own (SEPARATE_BLOCK). llvmpipe runs if-blocks masked
    // in line, so only loops end LLVM's basic blocks, and its instruction scheduler takes time
    // quadratic in a block's size: unrolled, the 24 inlined copies of the constraint and the
    // texture lookups (normal-mapped scenes) took LLVM over 50 minutes to compile.
    uint one = 1u + uint(row(x, 6).w);  // row 6's w is 0
#define SEPARATE_BLOCK for (uint once = 0u; once < one; ++once)
    vec2 diff[2];
    bool one_cell = true;
    for (uint t = 0u; t < 24u * c.k; ++t) {
        uint i = t / 24u, j = (t / 4u) % 6u, q = (t / 2u) & 1u;
        float sgn = (t & 1u) != 0u ? 1.0 : -1.0;
        if ((t & 3u) == 0u) {
            diff[0] = diff[1] = vec2(0.0);
            one_cell = true;
        }
        // Which point moves: vertex m of the chain, or x0 (m = -1) / y (m = k).
        int m = int(i) + int(j / 2u) - 1;
        ManifoldChain d = c;
        vec3 dx0 = vec3(0.0), dy = vec3(0.0);
        float e = sgn * h * float(q + 1u);
        if (m < 0) {
            if (!from_light) dx0 = e * ((j & 1u) != 0u ? et : es);
        } else if (m >= int(c.k)) {
            if (from_light) dy = e * ((j & 1u) != 0u ? et : es);
        } else {
            ManifoldVertex v = c.v[m];
            offset_u = fract(row(x, 6).yz + 0.37 * float(m));
            SEPARATE_BLOCK d.v[m] = vertex_at(v.prim, v.p + e * ((j & 1u) != 0u ? v.t : v.s));
            ivec2 cell_moved, cell;
            SEPARATE_BLOCK cell_moved = normal_map_cell(d.v[m]);
            SEPARATE_BLOCK cell = normal_map_cell(v);
            one_cell = one_cell && all(equal(cell_moved, cell));
        }
        vec2 constraint;
        SEPARATE_BLOCK constraint = constraint_of(kind, d, x0 + dx0, y + dy, i);
        diff[q] += sgn * constraint / (2.0 * h * float(q + 1u));
        if ((t & 3u) != 3u) continue;
        vec2 res;
        mat2 A, B, Cn;
        bool ok;
        SEPARATE_BLOCK ok = manifold_constraint_blocks(kind, c, x0, y, from_light, es, et, i, res, A, B, Cn);
        mat2 M = j < 2u ? A : j < 4u ? B : Cn;
        vec2 analytic = M[j & 1u];
        // Central differences at h and 2h, Richardson-extrapolated (error O(h^4)): near the
        // critical angle inside the sphere the O(h^2) term alone reaches 1e-3 at h = 1e-3.
        vec2 extrapolated = (4.0 * diff[0] - diff[1]) / 3.0;
        imageStore(outputImage, ivec2(x, 6 * int(i) + int(j)),
                   !ok ? vec4(1e30) : one_cell ? vec4(analytic, extrapolated) : vec4(-1e30));
    }
}
