// The Newton walk on a specular manifold (Zeltner et al. 2020 Sec. 4.3 and 5; Jakob & Marschner
// 2012 Sec. 4) without ray tracing: chain vertices with their differential geometry, the
// constraints of a chain x0 -> x1 .. xk -> y with fixed end points, their block-tridiagonal
// Jacobian and its block Thomas solve, the step of the first vertex, the generalized geometric
// term and the chain's throughput. Tracing (re-projection, seeds, visibility) is the caller's:
// manifold/sms.glsl runs every ray of a trial through one call site.
//
// Each vertex moves in the plane of its triangle, parameterised by an orthonormal basis (s, t)
// of that plane: steps, Jacobian blocks and determinants are in world units, so thresholds do
// not depend on how finely a mesh is tessellated.
#ifndef LOOM_MANIFOLD_WALK_GLSL
#define LOOM_MANIFOLD_WALK_GLSL

#include "lib/fresnel.glsl"
#include "lib/manifold/constraints.glsl"
#include "lib/material.glsl"
#include "lib/microfacet.glsl"
#include "lib/scene.glsl"
#include "lib/shading.glsl"

// Specular vertices a chain may have (two refractions through a slab or a sphere, short
// reflection chains).
#ifndef MANIFOLD_MAX_VERTICES
#define MANIFOLD_MAX_VERTICES 4
#endif

struct ManifoldVertex {
    vec3 p;
    vec3 ng;            // geometric normal (unit)
    vec3 n;             // shading normal the constraint scatters about (interpolated)
    vec3 s, t;          // orthonormal basis of the triangle plane: the vertex's parameters
    vec3 dn_ds, dn_dt;  // derivatives of n along s and t
    vec3 tangent;       // fixed reference (dp/du) of the half-vector frame
    float eta;          // int / ext IOR (dielectric)
    uint prim;
    uint shape;         // its material gives the throughput (manifold_chain_throughput)
    bool reflection;    // conductor: mirror reflection; dielectric: refraction
#ifdef MANIFOLD_ROUGH_CASTERS
    vec3 n_macro;       // a rough vertex's shading normal; n is then its offset normal
#endif
};

// Conductors (smooth or rough) reflect in a chain; dielectrics refract.
bool manifold_material_reflects(Material m) {
    uint t = material_type(m);
    return t == MATERIAL_CONDUCTOR || t == MATERIAL_ROUGH_CONDUCTOR;
}

bool manifold_material_rough(Material m) {
    uint t = material_type(m);
    return t == MATERIAL_ROUGH_CONDUCTOR || t == MATERIAL_ROUGH_DIELECTRIC;
}

// Whether a shape's material scatters as a manifold walk models it: smooth conductors reflect,
// smooth dielectrics refract (the walk's chains never reflect off glass). With
// MANIFOLD_ROUGH_CASTERS (set by the passes that sample offset normals) rough conductors and
// dielectrics too, about a sampled microfacet normal (manifold_rough_offset).
bool manifold_material_specular(Material m) {
    uint t = material_type(m);
#ifdef MANIFOLD_ROUGH_CASTERS
    if (manifold_material_rough(m)) return true;
#endif
    return t == MATERIAL_CONDUCTOR || t == MATERIAL_DIELECTRIC;
}

// A normal-mapped vertex: the shading normal the path tracer scatters about
// (shading.glsl normal_map_normal) and its derivatives along s and t, whose barycentric rates
// are bary_s, bary_t. Three parts change: the texel normal (bilinear: smooth within a texel
// cell), the interpolated normal, and the tangent frame, which is dp/du made orthogonal to the
// interpolated normal. (The frame's fallback for degenerate UVs, which has no texture
// variation to follow, is taken as fixed.)
void manifold_normal_map(inout ManifoldVertex v, SurfacePoint sp, Material mat, uint nmap,
                         vec2 bary_s, vec2 bary_t) {
    vec2 uv0, uv1, uv2;
    triangle_uvs(sp.prim, uv0, uv1, uv2);
    vec2 duv_s = (uv1 - uv0) * bary_s.x + (uv2 - uv0) * bary_s.y;
    vec2 duv_t = (uv1 - uv0) * bary_t.x + (uv2 - uv0) * bary_t.y;
    vec4 g_u, g_v;
    vec3 nt = normal_map_tangent_normal(mat, texture_fetch_grad(nmap, sp.uv, g_u, g_v).rgb);
    float decode = material_normal_slopes(mat) ? 1.0 : 2.0;  // d nt / d texel
    vec3 dnt_s = decode * (g_u.rgb * duv_s.x + g_v.rgb * duv_s.y);
    vec3 dnt_t = decode * (g_u.rgb * duv_t.x + g_v.rgb * duv_t.y);
#ifdef LOOM_TEST_NORMAL_MAP_CONSTANT_TEXELS  // the ablation the SMS tests must detect
    dnt_s = vec3(0.0);
    dnt_t = vec3(0.0);
#endif
    vec3 ns = sp.ns, T, B;
    shading_tangent_frame(ns, sp.tangent, T, B);
    vec3 m = nt.x * T + nt.y * B + nt.z * ns;
    float m_len = length(m);
    if (!(m_len > 0.0)) return;  // a broken texel: the path tracer keeps the interpolated normal too
    vec3 n = m / m_len;
    vec3 a = sp.tangent - ns * dot(ns, sp.tangent);
    float a_len = length(a);
    vec3 dn[2];
    for (int i = 0; i < 2; ++i) {
        vec3 dns = i == 0 ? v.dn_ds : v.dn_dt, dnt = i == 0 ? dnt_s : dnt_t;
        vec3 dT = a_len > 1e-12
                      ? manifold_d_normalize(T, a_len, -(dns * dot(ns, sp.tangent) +
                                                         ns * dot(dns, sp.tangent)))
                      : vec3(0.0);
        vec3 dB = cross(dns, T) + cross(ns, dT);
        vec3 dm = dnt.x * T + nt.x * dT + dnt.y * B + nt.y * dB + dnt.z * ns + nt.z * dns;
        dn[i] = manifold_d_normalize(n, m_len, dm);
    }
    v.n = n;
    v.dn_ds = dn[0];
    v.dn_dt = dn[1];
}

ManifoldVertex manifold_vertex(uint prim, vec2 bary) {
    SurfacePoint sp = surface_point(prim, bary);
    Material m = scene_material(scene_shape(sp.shape).material);
    ManifoldVertex v;
    v.p = sp.p;
    v.ng = sp.ng;
    v.n = sp.ns;
    v.prim = prim;
    v.shape = sp.shape;
    v.s = normalize(sp.dp_du);
    v.t = cross(sp.ng, v.s);
    // (du, dv) of a unit move along s or t: [dp_du dp_dv] (du, dv) = s (exact: s is in-plane).
    float g11 = dot(sp.dp_du, sp.dp_du), g12 = dot(sp.dp_du, sp.dp_dv), g22 = dot(sp.dp_dv, sp.dp_dv);
    float inv = 1.0 / (g11 * g22 - g12 * g12);
    vec2 rs = vec2(dot(sp.dp_du, v.s), dot(sp.dp_dv, v.s)), rt = vec2(dot(sp.dp_du, v.t), dot(sp.dp_dv, v.t));
    vec2 uv_s = inv * vec2(g22 * rs.x - g12 * rs.y, g11 * rs.y - g12 * rs.x);
    vec2 uv_t = inv * vec2(g22 * rt.x - g12 * rt.y, g11 * rt.y - g12 * rt.x);
    v.dn_ds = sp.dn_du * uv_s.x + sp.dn_dv * uv_s.y;
    v.dn_dt = sp.dn_du * uv_t.x + sp.dn_dv * uv_t.y;
    v.tangent = sp.dp_du;
    v.reflection = manifold_material_reflects(m);
    v.eta = material_eta(m);
    uint nmap = material_normal_map(m);
    if (nmap != MATERIAL_NO_TEXTURE) manifold_normal_map(v, sp, m, nmap, uv_s, uv_t);
    return v;
}

// Specular scattering of w (unit, away from the vertex) as the chain scatters at v.
SpecularScatter manifold_scatter(ManifoldVertex v, vec3 w) {
    return v.reflection ? specular_reflect(w, v.n) : specular_refract(w, v.n, v.eta);
}

// Constraint kinds (MANIFOLD_CONSTRAINT_* choice indices, registered by passes/sms).
// The half-vector frame at v: s_h = normalize(T - n (n.T)), t_h = n x s_h, and its derivative
// along a normal change dn.
void manifold_half_vector_frame(ManifoldVertex v, vec3 n, vec3 dn, out vec3 sh, out vec3 th,
                                out vec3 dsh, out vec3 dth) {
    vec3 a = v.tangent - n * dot(n, v.tangent);
    float len = length(a);
    sh = a / len;
    th = cross(n, sh);
    vec3 da = -(dn * dot(n, v.tangent) + n * dot(dn, v.tangent));
    dsh = manifold_d_normalize(sh, len, da);
    dth = cross(dn, sh) + cross(n, dsh);
}

#ifdef MANIFOLD_ROUGH_CASTERS
// A rough vertex (Zeltner et al. 2020 Sec. 5.3) scatters about an offset normal
// n' = o.x s_h + o.y t_h + o.z n: o is a microfacet normal of its material's distribution,
// drawn with density D(o) o.z from u in the vertex's half-vector frame and held fixed there
// while the walk moves the vertex, so that n' and its derivatives follow the frame (the
// generalized geometric term sees them). u stays the same for a whole estimate, its trials
// included. Smooth vertices keep n (n_macro = n).
void manifold_rough_offset(inout ManifoldVertex v, vec2 u) {
    v.n_macro = v.n;
    Material m = scene_material(scene_shape(v.shape).material);
    if (!manifold_material_rough(m)) return;
    float alpha = max(material_alpha(m), MICROFACET_MIN_ALPHA);
    vec3 o = microfacet_sample_normals(material_distribution(m), alpha, u);
    vec3 sh, th, dsh, dth, dn[2];
    for (int i = 0; i < 2; ++i) {
        vec3 dn_i = i == 0 ? v.dn_ds : v.dn_dt;
        manifold_half_vector_frame(v, v.n, dn_i, sh, th, dsh, dth);
        dn[i] = o.x * dsh + o.y * dth + o.z * dn_i;
    }
    v.n = o.x * sh + o.y * th + o.z * v.n;
    v.dn_ds = dn[0];
    v.dn_dt = dn[1];
}
#endif

// Constraint of vertex v between x_prev and x_next (kind: a MANIFOLD_CONSTRAINT_* index).
vec2 manifold_constraint(uint kind, vec3 x_prev, ManifoldVertex v, vec3 x_next, mat3 frame,
                         out bool valid) {
    if (kind == MANIFOLD_CONSTRAINT_HALF_VECTOR) {
        vec3 sh, th, dsh, dth;
        manifold_half_vector_frame(v, v.n, vec3(0.0), sh, th, dsh, dth);
        valid = true;
        return half_vector_constraint(normalize(x_prev - v.p), normalize(x_next - v.p), v.n, sh,
                                      th, v.eta, v.reflection, vec2(0.0));
    }
    return angle_difference_constraint_at(x_prev, v.p, x_next, v.n, v.eta, v.reflection, frame,
                                          valid);
}

// Its directional derivative when x_prev, v (with its normal) and x_next move by dx_prev, dx,
// dn, dx_next.
vec2 manifold_constraint_derivative(uint kind, vec3 x_prev, ManifoldVertex v, vec3 x_next,
                                    mat3 frame, vec3 dx_prev, vec3 dx, vec3 dn, vec3 dx_next) {
    if (kind == MANIFOLD_CONSTRAINT_HALF_VECTOR) {
        vec3 di = x_prev - v.p, dout = x_next - v.p;
        vec3 wi = normalize(di), wo = normalize(dout);
        vec3 dwi = manifold_d_normalize(wi, length(di), dx_prev - dx);
        vec3 dwo = manifold_d_normalize(wo, length(dout), dx_next - dx);
        vec3 sh, th, dsh, dth;
        manifold_half_vector_frame(v, v.n, dn, sh, th, dsh, dth);
        return half_vector_constraint_derivative(wi, wo, v.n, sh, th, v.eta, v.reflection, dwi,
                                                 dwo, dsh, dth);
    }
    return angle_difference_constraint_derivative(x_prev, v.p, x_next, v.n, v.eta, v.reflection,
                                                  frame, dx_prev, dx, dn, dx_next);
}

// The chain x0 -> v[0] .. v[k-1] -> y and what a Newton step needs of it.
// With end_at_infinity, y is a unit direction (a directional light): the last vertex's w_o is
// y wherever the vertex is.
struct ManifoldChain {
    ManifoldVertex v[MANIFOLD_MAX_VERTICES];
    mat3 frame[MANIFOLD_MAX_VERTICES];  // angle-difference frames, chosen from the seed
    uint k;
    bool end_at_infinity;
};

vec3 manifold_chain_prev(ManifoldChain c, uint i, vec3 x0) { return i == 0u ? x0 : c.v[i - 1u].p; }
vec3 manifold_chain_next(ManifoldChain c, uint i, vec3 y) {
    return i + 1u < c.k ? c.v[i + 1u].p : c.end_at_infinity ? c.v[i].p + y : y;
}

// Picks each vertex's angle frame from its current w_o (once per walk: the pole stays away
// from where the walk starts; see manifold_angle_frame).
void manifold_choose_frames(inout ManifoldChain c, vec3 y) {
    for (uint i = 0u; i < c.k; ++i)
        c.frame[i] = manifold_angle_frame(normalize(manifold_chain_next(c, i, y) - c.v[i].p));
}

// Largest |C_i| of the chain (-1 when a constraint is undefined there).
float manifold_chain_error(uint kind, ManifoldChain c, vec3 x0, vec3 y) {
    float e = 0.0;
    for (uint i = 0u; i < c.k; ++i) {
        bool valid;
        vec2 C = manifold_constraint(kind, manifold_chain_prev(c, i, x0), c.v[i],
                                     manifold_chain_next(c, i, y), c.frame[i], valid);
        if (!valid) return -1.0;
        e = max(e, length(C));
    }
    return e;
}

// A 2x2 block is singular when |det| is tiny against its scale (relative, so that the test is
// the same at any scene scale; the reference code's absolute 1e-6 is for unit-size scenes).
bool manifold_block_singular(mat2 m) {
    float scale = dot(m[0], m[0]) + dot(m[1], m[1]);
    float d = determinant(m);
    return !(abs(d) > 1e-7 * scale) || isinf(d) || isnan(d);
}

// The linearized chain, solved once per Newton iteration for two things at once:
//   - the Newton step dX = J^-1 C of the first vertex (the caller re-traces the rest of the
//     chain from it), and
//   - the end-point Jacobian by the implicit function theorem on C(x, e) = 0,
//     dx/de = -J^-1 dC/de: with from_light, |det(d(s,t)_1 / d(s,t)_y)| for the light point y
//     moving in the plane (es, et) (area lights); else |det(d(s,t)_k / d(s,t)_x0)| for x0
//     moving in its plane (es, et) (point lights).
// J is block tridiagonal with 2x2 blocks A_i = dC_i/d(s,t)_{i-1}, B_i = dC_i/d(s,t)_i,
// Cn_i = dC_i/d(s,t)_{i+1}, solved by the block Thomas algorithm. Row 0's A and row k-1's Cn
// hold the end points' derivatives (the elimination never reads them).
struct ManifoldLinearSolve {
    vec2 step;
    float error;          // max_i |C_i|; -1 when a constraint is undefined
    float endpoint_det;   // 0 when J is singular
    bool ok;              // false: undefined or singular
};

// Row i of the linearized chain: the residual C_i and its Jacobian blocks A = dC_i/d(s,t)_{i-1}
// (x0 along (es, et) for i = 0 unless from_light), B = dC_i/d(s,t)_i (normal change included),
// Cn = dC_i/d(s,t)_{i+1} (y along (es, et) for i = k-1 when from_light). False where the
// constraint is undefined.
bool manifold_constraint_blocks(uint kind, ManifoldChain c, vec3 x0, vec3 y, bool from_light,
                                vec3 es, vec3 et, uint i, out vec2 res, out mat2 A, out mat2 B,
                                out mat2 Cn) {
    vec3 xp = manifold_chain_prev(c, i, x0), xn = manifold_chain_next(c, i, y);
    ManifoldVertex v = c.v[i];
    bool valid;
    res = manifold_constraint(kind, xp, v, xn, c.frame[i], valid);
    A = mat2(0.0);
    B = mat2(0.0);
    Cn = mat2(0.0);
    if (!valid) return false;
    // Six directional derivatives: the previous vertex (or x0), this one, the next (or y), each
    // along its two parameters; one call site for all.
    vec3 z = vec3(0.0);
    vec2 col[6];
    for (uint j = 0u; j < 6u; ++j) {
        bool second = (j & 1u) != 0u;
        vec3 dxp = z, dx = z, dn = z, dxn = z;
        if (j < 2u) {
            if (i > 0u) dxp = second ? c.v[i - 1u].t : c.v[i - 1u].s;
            else if (!from_light) dxp = second ? et : es;
        } else if (j < 4u) {
            dx = second ? v.t : v.s;
            dn = second ? v.dn_dt : v.dn_ds;
            if (i + 1u == c.k && c.end_at_infinity) dxn = dx;  // x + y moves with x
        } else {
            if (i + 1u < c.k) dxn = second ? c.v[i + 1u].t : c.v[i + 1u].s;
            else if (from_light) dxn = second ? et : es;
        }
        col[j] = manifold_constraint_derivative(kind, xp, v, xn, c.frame[i], dxp, dx, dn, dxn);
    }
    A = mat2(col[0], col[1]);
    B = mat2(col[2], col[3]);
    Cn = mat2(col[4], col[5]);
    return true;
}

ManifoldLinearSolve manifold_linear_solve(uint kind, ManifoldChain c, vec3 x0, vec3 y,
                                          bool from_light, vec3 es, vec3 et) {
    ManifoldLinearSolve r;
    r.step = vec2(0.0);
    r.error = 0.0;
    r.endpoint_det = 0.0;
    r.ok = false;
    mat2 A[MANIFOLD_MAX_VERTICES], B[MANIFOLD_MAX_VERTICES], Cn[MANIFOLD_MAX_VERTICES];
    vec2 res[MANIFOLD_MAX_VERTICES];
    for (uint i = 0u; i < c.k; ++i) {
        if (!manifold_constraint_blocks(kind, c, x0, y, from_light, es, et, i, res[i], A[i], B[i],
                                        Cn[i])) {
            r.error = -1.0;
            return r;
        }
        r.error = max(r.error, length(res[i]));
    }
    // Right-hand sides: the residual (Newton) and the end point's derivative block.
    mat2 R[MANIFOLD_MAX_VERTICES];
    for (uint i = 0u; i < c.k; ++i) R[i] = mat2(0.0);
    if (from_light) R[c.k - 1u] = -Cn[c.k - 1u];
    else R[0] = -A[0];
    // Forward elimination.
    mat2 Bp[MANIFOLD_MAX_VERTICES];
    Bp[0] = B[0];
    for (uint i = 1u; i < c.k; ++i) {
        if (manifold_block_singular(Bp[i - 1u])) return r;
        mat2 M = A[i] * inverse(Bp[i - 1u]);
        Bp[i] = B[i] - M * Cn[i - 1u];
        res[i] -= M * res[i - 1u];
        R[i] -= M * R[i - 1u];
    }
    if (manifold_block_singular(Bp[c.k - 1u])) return r;
    // Back substitution (X: end-point Jacobian blocks, res: Newton step blocks).
    mat2 inv = inverse(Bp[c.k - 1u]);
    vec2 xs = inv * res[c.k - 1u];
    mat2 X = inv * R[c.k - 1u];
    float det_last = abs(determinant(X));
    for (int i = int(c.k) - 2; i >= 0; --i) {
        mat2 inv_i = inverse(Bp[i]);
        xs = inv_i * (res[i] - Cn[i] * xs);
        X = inv_i * (R[i] - Cn[i] * X);
    }
    r.step = xs;
    r.endpoint_det = from_light ? abs(determinant(X)) : det_last;
    r.ok = true;
    return r;
}

// Whether the converged chain scatters the way its materials do: at a reflection both
// neighbours lie on the same side of the geometric normal, at a refraction on opposite sides
// (the half-vector constraint also vanishes for the other type), with no segment shorter
// than min_length.
bool manifold_chain_types_valid(ManifoldChain c, vec3 x0, vec3 y, float min_length) {
    for (uint i = 0u; i < c.k; ++i) {
        vec3 a = manifold_chain_prev(c, i, x0) - c.v[i].p, b = manifold_chain_next(c, i, y) - c.v[i].p;
        if (length(a) < min_length || length(b) < min_length) return false;
        bool same_side = dot(a, c.v[i].ng) * dot(b, c.v[i].ng) > 0.0;
        if (same_side != c.v[i].reflection) return false;
    }
    return true;
}

// Generalized geometric term (Zeltner Sec. 4.4; Jakob & Marschner 2012 Sec. 4.3) from the
// end-point Jacobian of manifold_linear_solve. Area light (from_light):
// d omega_x0 / dA_y = |cos theta_1| / |x1 - x0|^2 |det(dx1/dy)|. Point light:
// d omega_y / dA_x0 = |cos theta_k| / |y - x_k|^2 |det(dx_k/dx0)| (irradiance = I times this).
// Directional light (end_at_infinity): the irradiance at x0 is E times |cos theta_k| |det|.
float manifold_geometric_term(ManifoldChain c, vec3 x0, vec3 y, bool from_light, float det) {
    ManifoldVertex v = from_light ? c.v[0] : c.v[c.k - 1u];
    if (!from_light && c.end_at_infinity) return abs(dot(v.ng, y)) * det;
    vec3 d = (from_light ? x0 : y) - v.p;
    float r2 = dot(d, d);
    return abs(dot(v.ng, d)) / (r2 * sqrt(r2)) * det;
}

// Throughput of the chain's specular vertices for radiance flowing y -> x0, as the path
// tracer's delta BSDF samples weigh it: conductor specular F, dielectric transmittance
// (1 - F) / eta^2 with eta across the interface from x0's side (bsdf.glsl dielectric_sample).
// Zero for a one-sided conductor seen from behind. Flux from a point or directional light
// (irradiance I d omega_y / dA_x0, or E times the beam's area ratio) crosses the chain with
// T / (radiance_scale etendue_scale):
//  - radiance_scale, the product of the 1/eta^2 factors, (n_x0 / n_y)^2: energy, no radiance
//    compression;
//  - etendue_scale, the product of |l.n_g| |c.m| / (|c.n_g| |l.m|) (c towards x0, l towards y):
//    a vertex that scatters about a normal m other than its geometric normal n_g (interpolated
//    or mapped shading normals, a rough vertex's offset normal) changes the beam's etendue by
//    this (reflection keeps solid angle about m, refraction scales it by eta^2 |c.m| / |l.m|),
//    while the path tracer's specular lobes keep radiance. 1 on flat geometry.
// An area light's radiance crosses with T.
vec3 manifold_chain_throughput(ManifoldChain c, vec3 x0, vec3 y, out float radiance_scale,
                               out float etendue_scale) {
    vec3 T = vec3(1.0);
    radiance_scale = 1.0;
    etendue_scale = 1.0;
    for (uint i = 0u; i < c.k; ++i) {
        ManifoldVertex v = c.v[i];
        // Material data stays out of the vertex: a walk carries two chains per lane.
        Material m = scene_material(scene_shape(v.shape).material);
        vec3 wo = normalize(manifold_chain_prev(c, i, x0) - v.p);  // towards the camera side
        vec3 wl = normalize(manifold_chain_next(c, i, y) - v.p);   // towards the light
        float cos_o = dot(wo, v.n);
#ifndef LOOM_TEST_FLUX_FORM_KEPT  // (the ablation the SMS tests must detect)
        etendue_scale *= abs(dot(wl, v.ng)) * abs(cos_o) / (abs(dot(wo, v.ng)) * abs(dot(wl, v.n)));
#endif
        if (v.reflection) {
            if (cos_o <= 0.0 && !material_two_sided(m)) return vec3(0.0);
            T *= m.specular.rgb * fresnel_conductor(abs(cos_o), m.cond_eta.rgb, m.cond_k.rgb);
        } else {
            float cos_t;
            float F = fresnel_dielectric(cos_o, v.eta, cos_t);
            float e = cos_o >= 0.0 ? v.eta : 1.0 / v.eta;
            T *= m.transmittance.rgb * ((1.0 - F) / (e * e));
            radiance_scale /= e * e;
        }
    }
    return T;
}

#ifdef MANIFOLD_ROUGH_CASTERS
// What a chain's rough vertices weigh#ifdef MANIFOLD_ROUGH_CASTERS
// What a chain's rough vertices weigh beyond their specular scattering about the offset normal
// m (manifold_rough_offset: density D(m) (m.n)). With c towards the camera side and l towards
// the light, f |l.n| d omega_l = F D(m) G2(c, l, m) |c.m| / |c.n| dm at a rough vertex
// (Walter et al. 2007 Eq. 14 and 17 turn d omega_l into dm; transmitted radiance scales by
// 1/eta^2 as through smooth glass). For fixed m the chain is specular, and the throughput
// (Fresnel at c.m) and the generalized geometric term take it from there: what remains is
// G2 |c.m| / (|c.n| |m.n|), D cancelling against the density.
float manifold_chain_rough_weight(ManifoldChain c, vec3 x0, vec3 y) {
    float w = 1.0;
    for (uint i = 0u; i < c.k; ++i) {
        ManifoldVertex v = c.v[i];
        Material m = scene_material(scene_shape(v.shape).material);
        if (!manifold_material_rough(m)) continue;
        vec3 wc = normalize(manifold_chain_prev(c, i, x0) - v.p);
        vec3 wl = normalize(manifold_chain_next(c, i, y) - v.p);
        float c_n = dot(wc, v.n_macro);
        if (v.reflection && c_n <= 0.0 && !material_two_sided(m)) return 0.0;
        // The frame of the side c is on; m faces it too (microfacet.glsl's convention).
        vec3 n = c_n >= 0.0 ? v.n_macro : -v.n_macro;
        vec3 mn = dot(v.n, n) >= 0.0 ? v.n : -v.n;
        vec3 a, b;
        orthonormal_basis(n, a, b);
        mat3 to_local = transpose(mat3(a, b, n));
        vec3 cl = to_local * wc, ll = to_local * wl, ml = to_local * mn;
        float g2 = microfacet_g2(material_distribution(m), max(material_alpha(m), MICROFACET_MIN_ALPHA),
                                 cl, ll, ml);
#ifdef LOOM_TEST_ROUGH_WEIGHT_OMITTED  // the ablation the SMS tests must detect
        continue;
#endif
        w *= g2 * abs(dot(cl, ml)) / (abs(cl.z) * ml.z);
    }
    return w;
}
#endif

#endif
