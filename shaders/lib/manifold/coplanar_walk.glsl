// Manifold next-event estimation with dimension reduction (Granizo-Hidalgo & Holzschuch 2024):
// the specular vertex M between a receiver point P and a light point L lies on the curve of
// points whose interpolated normal is in the plane (P, L, M) (coplanarity). On a triangle with
// vertex normals that curve is a conic in the barycentrics (Eq. 10-12); the walk follows it
// across triangles through the adjacency buffer (bvh.glsl) from the point where the segment
// P -> L meets the specular surface, watches the refraction (or reflection) condition f for a
// sign change and bisects there. No derivatives, no re-projection rays.
//
// Decisions where the paper is silent (passes/mnee_dr/README.md has the reasons):
// - f's sign: r x w_L is along the normal of the plane (P, L, M); we take its component on
//   k = normalize((L - P) x (M - P)), which is continuous along the walk (it only flips where M
//   crosses the line PL, i.e. at the start point, where the walk takes its limit). The paper's
//   t . (r x w_L) has the same roots plus spurious ones where the tangent lies in the plane.
// - The arc inside a triangle is parameterised from its entry point A by the angle of a line
//   through A (each such line meets the conic once more: the rational parameterisation), or,
//   where the arc is nearly straight, by distance along the tangent with points found on the
//   perpendicular. Exits are ordered by that parameter, which handles two or four crossings.
// - Bisection splits the triangle by such a line; it stops when the bracket's two points are
//   closer than the tolerance times the triangle's longest edge, or after max_bisections.
// - Walk direction: towards the first exit where f changes sign, else where |f| decreases;
//   the other direction next if the first one fails (both_directions).
// - A root is a solution when r points towards the light (not away: r x w_L also vanishes
//   there) and the sine between them is below 1e-3 (a sign change across total internal
//   reflection or a discontinuity is not a root).
#ifndef LOOM_MANIFOLD_COPLANAR_WALK_GLSL
#define LOOM_MANIFOLD_COPLANAR_WALK_GLSL

#include "lib/bvh.glsl"
#include "lib/manifold/constraints.glsl"
#include "lib/scene.glsl"
#include "lib/shading.glsl"

// Why a walk ended (CoplanarResult.status).
const uint COPLANAR_SOLVED = 0u;
const uint COPLANAR_NO_START = 1u;   // the segment P -> L does not cross a caster
const uint COPLANAR_BOUNDARY = 2u;   // the curve left the mesh through a boundary edge
const uint COPLANAR_CAP = 3u;        // max_triangles crossed without a root
const uint COPLANAR_TIR = 4u;        // the curve reached total internal reflection
const uint COPLANAR_DEGENERATE = 5u; // a singular point of the curve or a degenerate triangle
const uint COPLANAR_NO_ROOT = 6u;    // a closed curve (ellipse) without a valid root
const uint COPLANAR_OCCLUDED = 7u;   // solved, but P -> M or M -> L is blocked
const uint COPLANAR_STATUS_COUNT = 8u;

struct CoplanarSettings {
    uint max_triangles;         // triangles a walk may enter (both directions together)
    uint max_bisections;        // bisection steps per bracket
    float bisection_tolerance;  // bracket width, relative to the triangle's longest edge
    bool both_directions;       // walk the other way from the start point when one way fails
};

// The query: the receiver point and the light point (or the unit direction towards a
// directional light); w is the unit direction of the line P -> L.
struct CoplanarQuery {
    vec3 P;
    vec3 L;
    bool directional;
    vec3 w;
};

CoplanarQuery coplanar_query(vec3 P, vec3 L, bool directional) {
    CoplanarQuery q;
    q.P = P;
    q.L = L;
    q.directional = directional;
    q.w = directional ? normalize(L) : normalize(L - P);
    return q;
}

struct CoplanarTriangle {
    vec3 v0, e1, e2;    // V0, V1 - V0, V2 - V0 (world space)
    vec3 n0, dn1, dn2;  // vertex normal n0, n1 - n0, n2 - n0: N(a, b) = n0 + a dn1 + b dn2
    uvec3 vid;          // vertex indices: edges are matched by them across triangles
    uint prim;
    float eta;          // int / ext, N pointing outside
    bool reflection;    // conductor: mirror reflection, else refraction
    float size;         // longest edge
    mat3 A;             // the conic x^T A x = 0, x = (a, b, 1) (Eq. 10-12), symmetric
};

// Eq. 10-12: N(x) . (w x (M(x) - P)) = x^T [N]^T [Q] x with [N] = (dn1, dn2, n0) and
// [Q] = (w x e1, w x e2, w x (V0 - P)); only the symmetric part of [N]^T [Q] matters.
CoplanarTriangle coplanar_triangle(uint prim, CoplanarQuery q) {
    CoplanarTriangle t;
    uvec4 tri = scene_triangle(prim);
    t.vid = tri.xyz;
    t.prim = prim;
    VertexGpu a = scene_vertex(tri.x), b = scene_vertex(tri.y), c = scene_vertex(tri.z);
    t.v0 = a.position_u.xyz;
    t.e1 = b.position_u.xyz - t.v0;
    t.e2 = c.position_u.xyz - t.v0;
    t.size = max(length(t.e1), max(length(t.e2), length(t.e2 - t.e1)));
    vec3 ng = cross(t.e1, t.e2);
    ng = dot(ng, ng) > 0.0 ? normalize(ng) : vec3(0.0);
    vec3 n0 = a.normal_v.xyz, n1 = b.normal_v.xyz, n2 = c.normal_v.xyz;
    if (dot(n0, n0) == 0.0 || dot(n1, n1) == 0.0 || dot(n2, n2) == 0.0) n0 = n1 = n2 = ng;
    t.n0 = n0;
    t.dn1 = n1 - n0;
    t.dn2 = n2 - n0;
    Material m = scene_material(scene_shape(tri.w).material);
    t.reflection = material_type(m) == MATERIAL_CONDUCTOR;
    t.eta = material_eta(m);
    mat3 N = mat3(t.dn1, t.dn2, t.n0);
    mat3 Q = mat3(cross(q.w, t.e1), cross(q.w, t.e2), cross(q.w, t.v0 - q.P));
    mat3 B = transpose(N) * Q;
    t.A = 0.5 * (B + transpose(B));
    return t;
}

vec3 coplanar_position(CoplanarTriangle t, vec2 x) { return t.v0 + x.x * t.e1 + x.y * t.e2; }
vec3 coplanar_normal(CoplanarTriangle t, vec2 x) { return t.n0 + x.x * t.dn1 + x.y * t.dn2; }
float coplanar_conic(CoplanarTriangle t, vec2 x) {
    vec3 h = vec3(x, 1.0);
    return dot(h, t.A * h);
}
// Gradient of the conic in (a, b); its perpendicular is the tangent (Eq. 14-15).
vec2 coplanar_gradient(CoplanarTriangle t, vec2 x) { return 2.0 * (t.A * vec3(x, 1.0)).xy; }
mat2 coplanar_quadratic(CoplanarTriangle t) { return mat2(t.A[0].xy, t.A[1].xy); }
vec3 coplanar_world(CoplanarTriangle t, vec2 d) { return d.x * t.e1 + d.y * t.e2; }

// Edge k of the triangle runs from vertex k to vertex k + 1: x(s) = a + s b in (a, b, 1).
vec3 coplanar_edge_origin(uint k) {
    return k == 0u ? vec3(0.0, 0.0, 1.0) : (k == 1u ? vec3(1.0, 0.0, 1.0) : vec3(0.0, 1.0, 1.0));
}
vec3 coplanar_edge_direction(uint k) {
    return k == 0u ? vec3(1.0, 0.0, 0.0) : (k == 1u ? vec3(-1.0, 1.0, 0.0) : vec3(0.0, -1.0, 0.0));
}
// Points into the triangle across edge k (in (a, b)).
vec2 coplanar_edge_inward(uint k) {
    return k == 0u ? vec2(0.0, 1.0) : (k == 1u ? vec2(-1.0, -1.0) : vec2(1.0, 0.0));
}

// Real roots of c2 s^2 + c1 s + c0 (count returned; a linear equation when c2 is negligible).
uint coplanar_quadratic_roots(float c2, float c1, float c0, out float s0, out float s1) {
    s0 = s1 = 0.0;
    float scale = max(abs(c1), abs(c0));
    if (abs(c2) <= 1e-7 * scale) {
        if (c1 == 0.0) return 0u;
        s0 = -c0 / c1;
        return 1u;
    }
    float disc = c1 * c1 - 4.0 * c2 * c0;
    if (disc < 0.0) return 0u;
    float qq = -0.5 * (c1 + (c1 >= 0.0 ? 1.0 : -1.0) * sqrt(disc));
    s0 = qq / c2;
    s1 = qq != 0.0 ? c0 / qq : s0;
    return 2u;
}

// Edge crossings of the conic (Eq. 22-24): roots of F(a + s b) in [0, 1].
uint coplanar_edge_crossings(CoplanarTriangle t, uint k, out float s0, out float s1) {
    vec3 a = coplanar_edge_origin(k), b = coplanar_edge_direction(k);
    float r0, r1;
    uint n = coplanar_quadratic_roots(dot(b, t.A * b), 2.0 * dot(a, t.A * b), dot(a, t.A * a),
                                      r0, r1);
    uint m = 0u;
    s0 = s1 = 0.0;
    const float eps = 1e-6;
    if (n >= 1u && r0 >= -eps && r0 <= 1.0 + eps) s0 = clamp(r0, 0.0, 1.0), m = 1u;
    if (n == 2u && r1 >= -eps && r1 <= 1.0 + eps) {
        if (m == 0u) s0 = clamp(r1, 0.0, 1.0);
        else s1 = clamp(r1, 0.0, 1.0);
        m++;
    }
    return m;
}

vec2 coplanar_edge_point(uint k, float s) {
    vec3 p = coplanar_edge_origin(k) + s * coplanar_edge_direction(k);
    return p.xy;
}

// The arc of the curve from an entry point a, in the walk direction t (unit, in (a, b)).
struct CoplanarArc {
    vec2 a, t;
    bool line;     // nearly straight: tau = distance along t, points on the perpendicular
    float theta;   // angle of t
    float sigma;   // +-1: the sense in which the line angle advances along the walk
};

CoplanarArc coplanar_arc(CoplanarTriangle tri, vec2 a, vec2 t) {
    CoplanarArc arc;
    arc.a = a;
    arc.t = t;
    arc.theta = atan(t.y, t.x);
    vec2 g = coplanar_gradient(tri, a);
    float curv = dot(t, coplanar_quadratic(tri) * t);
    // Curvature radius |g| / (2 |t^T H t|) in barycentric units: a nearly straight arc is
    // followed along its tangent (the angle parameter degenerates there).
    arc.line = abs(curv) * 50.0 * 2.0 < length(g);
    // A line through a at the angle theta + delta meets the conic again at
    // s = -(g . u) / (u^T H u) ~ delta (o |g|) / (t^T H t): forward for sign(delta) = sigma.
    vec2 pg = vec2(-g.y, g.x);
    arc.sigma = (curv >= 0.0 ? 1.0 : -1.0) * (dot(pg, t) >= 0.0 ? 1.0 : -1.0);
    return arc;
}

// The arc parameter of a point c of the conic (tau > 0 ahead of a).
float coplanar_arc_param(CoplanarArc arc, vec2 c) {
    vec2 d = c - arc.a;
    if (arc.line) return dot(d, arc.t);
    float th = atan(d.y, d.x);
    return mod(arc.sigma * (th - arc.theta), 3.14159265358979);
}

// The point of the arc at parameter tau (ok = false where the line misses the conic).
vec2 coplanar_arc_point(CoplanarTriangle tri, CoplanarArc arc, float tau, out bool ok) {
    ok = true;
    if (arc.line) {
        vec2 b = arc.a + tau * arc.t, n = vec2(-arc.t.y, arc.t.x);
        mat2 H = coplanar_quadratic(tri);
        float s0, s1;
        uint m = coplanar_quadratic_roots(dot(n, H * n), dot(coplanar_gradient(tri, b), n),
                                          coplanar_conic(tri, b), s0, s1);
        if (m == 0u) {
            ok = false;
            return b;
        }
        float s = (m == 2u && abs(s1) < abs(s0)) ? s1 : s0;
        return b + s * n;
    }
    float th = arc.theta + arc.sigma * tau;
    vec2 u = vec2(cos(th), sin(th));
    float den = dot(u, coplanar_quadratic(tri) * u);
    float num = dot(coplanar_gradient(tri, arc.a), u);
    if (den == 0.0) {
        ok = false;
        return arc.a;
    }
    return arc.a - (num / den) * u;
}

// The refraction (reflection) condition at barycentrics x (Eq. 19-21 with the sign of the
// component along k): r = the direction from P scattered at M, f = (r x w_L) . k. With
// use_k the given k is used (the start point, where the plane (P, L, M) is undefined).
struct CoplanarCondition {
    float f;
    bool valid;        // false: total internal reflection, or a degenerate plane
    bool towards;      // r points towards the light (not away from it)
    float sine;        // |r x w_L|
};

CoplanarCondition coplanar_condition(CoplanarTriangle tri, vec2 x, CoplanarQuery q, vec3 k,
                                     bool use_k) {
    CoplanarCondition c;
    vec3 M = coplanar_position(tri, x);
    vec3 n = normalize(coplanar_normal(tri, x));
    vec3 wP = normalize(q.P - M);
    vec3 wL = q.directional ? q.L : normalize(q.L - M);
    SpecularScatter s = tri.reflection ? specular_reflect(wP, n) : specular_refract(wP, n, tri.eta);
    if (!use_k) k = cross(q.w, M - q.P);
    float kl = length(k);
    c.valid = s.valid && kl > 0.0 && !any(isnan(n));
    vec3 cr = cross(s.w, wL);
    c.f = c.valid ? dot(cr, k / kl) : 0.0;
    c.sine = length(cr);
    c.towards = dot(s.w, wL) > 0.0;
    return c;
}

struct CoplanarResult {
    uint status;       // COPLANAR_*: the solution, or how the first direction failed
    uint status_other; // how the other direction ended (both_directions), else status
    uint prim;         // the solution's triangle
    vec2 bary;         // its barycentrics (Hit.bary convention)
    vec3 M;
    uint triangles;    // triangles entered (both directions)
    uint bisections;   // bisection steps
};

// Bisection of f on the arc between tau_lo (f_lo) and tau_hi (f_hi), opposite signs. Returns
// whether the bracket closed on a valid root (then x is its barycentrics).
bool coplanar_bisect(CoplanarTriangle tri, CoplanarArc arc, CoplanarQuery q, CoplanarSettings cs,
                     float tau_lo, float f_lo, float tau_hi, float f_hi, inout uint steps,
                     out vec2 x) {
    float tol = cs.bisection_tolerance * tri.size;
    bool ok;
    for (uint i = 0u; i < cs.max_bisections; ++i) {
        vec2 xl = coplanar_arc_point(tri, arc, tau_lo, ok);
        vec2 xh = coplanar_arc_point(tri, arc, tau_hi, ok);
        if (length(coplanar_world(tri, xh - xl)) < tol) break;
        steps++;
        float tau = 0.5 * (tau_lo + tau_hi);
        vec2 xm = coplanar_arc_point(tri, arc, tau, ok);
        if (!ok) return false;
        CoplanarCondition cm = coplanar_condition(tri, xm, q, vec3(0.0), false);
        if (!cm.valid) return false;
        if ((cm.f < 0.0) == (f_lo < 0.0)) tau_lo = tau, f_lo = cm.f;
        else tau_hi = tau, f_hi = cm.f;
    }
    // Regula falsi inside the final bracket.
    float w = f_lo / (f_lo - f_hi);
    x = coplanar_arc_point(tri, arc, mix(tau_lo, tau_hi, clamp(w, 0.0, 1.0)), ok);
    if (!ok || any(isnan(x))) return false;
    CoplanarCondition c = coplanar_condition(tri, x, q, vec3(0.0), false);
    return c.valid && c.towards && c.sine < 1e-3;
}

// The arc parameter next to the boundary of total internal reflection between tau_valid
// (the condition is defined there) and tau_invalid (it is not), on the valid side, by
// bisection on validity.
float coplanar_valid_boundary(CoplanarTriangle tri, CoplanarArc arc, CoplanarQuery q,
                              CoplanarSettings cs, float tau_valid, float tau_invalid,
                              inout uint steps) {
    float span = abs(tau_invalid - tau_valid);
    for (uint i = 0u; i < cs.max_bisections && abs(tau_invalid - tau_valid) > 1e-6 * span; ++i) {
        steps++;
        float mid = 0.5 * (tau_valid + tau_invalid);
        bool ok;
        vec2 x = coplanar_arc_point(tri, arc, mid, ok);
        if (ok && coplanar_condition(tri, x, q, vec3(0.0), false).valid) tau_valid = mid;
        else tau_invalid = mid;
    }
    return tau_valid;
}

// The first exit of the arc from the triangle: edge, its parameter s on the edge, the
// barycentrics and the arc parameter. entry_edge (3: none, the start triangle) and entry_s
// say where the arc came in: of the entry edge's crossings, the one nearest entry_s is the
// entry itself. (Its recomputed root moves with the triangle's size: F's terms are of the
// order of |M - P| while its gradient is of the order of the triangle, so at a million
// triangles float rounding puts it 1e-5 .. 1e-4 away in barycentrics, and a distance test
// would take it for an exit back out.)
bool coplanar_exit(CoplanarTriangle tri, CoplanarArc arc, uint entry_edge, float entry_s,
                   out uint edge, out float s_exit, out vec2 x_exit, out float tau_exit) {
    tau_exit = 1e30;
    edge = 0u;
    s_exit = 0.0;
    x_exit = arc.a;
    bool found = false;
    for (uint k = 0u; k < 3u; ++k) {
        float s[2];
        uint n = coplanar_edge_crossings(tri, k, s[0], s[1]);
        uint skip = 2u;
        if (k == entry_edge && n > 0u)
            skip = (n == 2u && abs(s[1] - entry_s) < abs(s[0] - entry_s)) ? 1u : 0u;
        for (uint i = 0u; i < n; ++i) {
            if (i == skip) continue;
            vec2 c = coplanar_edge_point(k, s[i]);
            if (length(c - arc.a) < 1e-5) continue;  // the start point, or a vertex
            float tau = coplanar_arc_param(arc, c);
            if (!(tau > 1e-6) || tau >= tau_exit) continue;
            tau_exit = tau;
            edge = k;
            s_exit = s[i];
            x_exit = c;
            found = true;
        }
    }
    return found;
}

// The unit walk tangent at x: perpendicular to the gradient, on the side of `towards` (in
// (a, b)); false at a singular point.
bool coplanar_tangent(CoplanarTriangle tri, vec2 x, vec2 towards, out vec2 t) {
    vec2 g = coplanar_gradient(tri, x);
    t = vec2(-g.y, g.x);
    float len = length(t);
    if (!(len > 0.0)) return false;
    t /= len;
    if (dot(t, towards) < 0.0) t = -t;
    return true;
}

// Walks from the start point (prim, bary) in the direction dir0 (unit, barycentric) until f
// changes sign at a valid root, a boundary, total internal reflection or the cap.
uint coplanar_walk_from(CoplanarQuery q, CoplanarSettings cs, uint prim0, vec2 bary0, vec2 dir0,
                        inout CoplanarResult res) {
    CoplanarTriangle tri = coplanar_triangle(prim0, q);
    vec2 a = bary0, t = dir0;
    bool start = true;
    uint entry_edge = 3u;  // none: the start point is inside
    float entry_s = 0.0;
    bool have_f;  // f is defined at the entry point (no total internal reflection there)
    float f_a;
    {
        // At the start point the plane (P, L, M) is undefined; along the walk it tends to the
        // plane spanned by w and the walk tangent.
        vec3 k0 = cross(q.w, coplanar_world(tri, t));
        CoplanarCondition c0 = coplanar_condition(tri, a, q, k0, true);
        // Totally internally reflected on the line PL (P far from the light, under water):
        // the walk crosses that region with no sign to watch until the curve refracts again.
        have_f = c0.valid;
        f_a = c0.f;
    }
    while (res.triangles < cs.max_triangles) {
        res.triangles++;
        CoplanarArc arc = coplanar_arc(tri, a, t);
        uint edge;
        float s_exit, tau_exit;
        vec2 x_exit;
        if (!coplanar_exit(tri, arc, entry_edge, entry_s, edge, s_exit, x_exit, tau_exit)) {
            if (!start || arc.line) return COPLANAR_DEGENERATE;
            if (!have_f) return COPLANAR_TIR;
            // An ellipse inside the start triangle: the angle parameter goes round it back to
            // the start, where f's limit is -f_a (k flips across the line PL). Bracket the
            // first valid sign change among 8 samples.
            float tau_prev = 0.0, f_prev = f_a;
            for (uint j = 1u; j <= 8u; ++j) {
                float tau = 3.14159265 * float(j) / 8.0;
                float fj = -f_a;
                if (j < 8u) {
                    bool ok;
                    vec2 xj = coplanar_arc_point(tri, arc, tau, ok);
                    CoplanarCondition cj = coplanar_condition(tri, xj, q, vec3(0.0), false);
                    if (!ok || !cj.valid) return COPLANAR_TIR;
                    fj = cj.f;
                } else {
                    tau = 3.14159265 * (1.0 - 1e-4);
                }
                vec2 x;
                if ((fj < 0.0) != (f_prev < 0.0) &&
                    coplanar_bisect(tri, arc, q, cs, tau_prev, f_prev, tau, fj, res.bisections, x)) {
                    res.prim = tri.prim;
                    res.bary = x;
                    res.M = coplanar_position(tri, x);
                    return COPLANAR_SOLVED;
                }
                tau_prev = tau;
                f_prev = fj;
            }
            return COPLANAR_NO_ROOT;
        }
        CoplanarCondition ce = coplanar_condition(tri, x_exit, q, vec3(0.0), false);
        if (!have_f && ce.valid) {
            // The curve leaves the region of total internal reflection in this triangle: watch
            // f's sign from the first point that refracts.
            float tau_v = coplanar_valid_boundary(tri, arc, q, cs, tau_exit, 0.0, res.bisections);
            bool ok;
            vec2 xv = coplanar_arc_point(tri, arc, tau_v, ok);
            CoplanarCondition cv = coplanar_condition(tri, xv, q, vec3(0.0), false);
            if (!ok || !cv.valid) return COPLANAR_TIR;
            have_f = true;
            vec2 x;
            if ((cv.f < 0.0) != (ce.f < 0.0) &&
                coplanar_bisect(tri, arc, q, cs, tau_v, cv.f, tau_exit, ce.f, res.bisections, x)) {
                res.prim = tri.prim;
                res.bary = x;
                res.M = coplanar_position(tri, x);
                return COPLANAR_SOLVED;
            }
        } else if (!have_f) {
            // Still totally internally reflected: on to the neighbour.
        } else if (!ce.valid) {
            // Total internal reflection before the exit (large triangles reach grazing angles):
            // the last point of the arc that still refracts closes the search in this
            // direction; a root before it is still found.
            float tau_v = coplanar_valid_boundary(tri, arc, q, cs, 0.0, tau_exit, res.bisections);
            bool ok;
            vec2 xv = coplanar_arc_point(tri, arc, tau_v, ok);
            CoplanarCondition cv = coplanar_condition(tri, xv, q, vec3(0.0), false);
            vec2 x;
            if (ok && cv.valid && (cv.f < 0.0) != (f_a < 0.0) &&
                coplanar_bisect(tri, arc, q, cs, 0.0, f_a, tau_v, cv.f, res.bisections, x)) {
                res.prim = tri.prim;
                res.bary = x;
                res.M = coplanar_position(tri, x);
                return COPLANAR_SOLVED;
            }
            return COPLANAR_TIR;
        } else if ((ce.f < 0.0) != (f_a < 0.0)) {
            vec2 x;
            if (coplanar_bisect(tri, arc, q, cs, 0.0, f_a, tau_exit, ce.f, res.bisections, x)) {
                res.prim = tri.prim;
                res.bary = x;
                res.M = coplanar_position(tri, x);
                return COPLANAR_SOLVED;
            }
        }
        // Across the exit edge to the neighbour (Sec. 4: the adjacency buffer).
        vec2 out_t;
        if (!coplanar_tangent(tri, x_exit, -coplanar_edge_inward(edge), out_t))
            return COPLANAR_DEGENERATE;
        vec3 t_world = coplanar_world(tri, out_t);
        int next = bvh_adjacent(tri.prim)[edge];
        if (next < 0) return COPLANAR_BOUNDARY;
        uint va = tri.vid[edge], vb = tri.vid[(edge + 1u) % 3u];
        tri = coplanar_triangle(uint(next), q);
        // The same edge in the neighbour, and the same point on it.
        uint entry = 3u;
        float s_in = 0.0;
        for (uint k = 0u; k < 3u; ++k) {
            uint ka = tri.vid[k], kb = tri.vid[(k + 1u) % 3u];
            if (ka == va && kb == vb) entry = k, s_in = s_exit;
            else if (ka == vb && kb == va) entry = k, s_in = 1.0 - s_exit;
        }
        if (entry == 3u) return COPLANAR_BOUNDARY;
        a = coplanar_edge_point(entry, s_in);
        entry_edge = entry;
        entry_s = s_in;
        // The tangent continues into the new triangle; where the curve runs along the edge,
        // the world tangent's orientation decides (kept across triangles).
        vec2 in_t;
        if (!coplanar_tangent(tri, a, coplanar_edge_inward(entry), in_t))
            return COPLANAR_DEGENERATE;
        if (abs(dot(in_t, normalize(coplanar_edge_inward(entry)))) < 1e-4 &&
            dot(coplanar_world(tri, in_t), t_world) < 0.0)
            in_t = -in_t;
        t = in_t;
        f_a = ce.f;
        start = false;
    }
    return COPLANAR_CAP;
}

// The start point: where the line PL meets a caster (BVH mask: casters only). Every point of
// that line is on the conic (w x (M - P) = 0). Refraction separates P and L, so the segment
// P -> L is tried first (attempt 0, the paper's start); a mirror on their side is reached by
// the line beyond L (attempt 1, point and area lights) or behind P (attempt 2).
struct CoplanarStartRay {
    vec3 o, d;
    float tmin, tmax;
};

const uint COPLANAR_START_ATTEMPTS = 3u;

bool coplanar_start_ray(CoplanarQuery q, uint attempt, out CoplanarStartRay r) {
    float eps = 1e-4 * max(1.0, max(abs(q.P.x), max(abs(q.P.y), abs(q.P.z))));
    r.o = q.P;
    r.d = q.w;
    r.tmin = eps;
    r.tmax = q.directional ? 1e30 : length(q.L - q.P) * (1.0 - 1e-4);
    if (attempt == 1u) {
        if (q.directional) return false;
        r.o = q.L;
        r.tmin = 1e-4 * max(1.0, max(abs(q.L.x), max(abs(q.L.y), abs(q.L.z))));
        r.tmax = 1e30;
    } else if (attempt == 2u) {
        r.d = -q.w;
        r.tmax = 1e30;
    }
    return attempt < COPLANAR_START_ATTEMPTS;
}
const uint COPLANAR_START_MASK = SHAPE_CAUSTIC_CASTER;

// The whole walk from the start ray's result (found, hit): one direction, then
// (both_directions) the other. Kernels trace the start ray at their one call site.
CoplanarResult coplanar_walk_from_start(CoplanarQuery q, CoplanarSettings cs, bool found,
                                        Hit hit) {
    CoplanarResult res;
    res.status = COPLANAR_NO_START;
    res.status_other = COPLANAR_NO_START;
    res.prim = 0u;
    res.bary = vec2(0.0);
    res.M = vec3(0.0);
    res.triangles = 0u;
    res.bisections = 0u;
    if (!found) return res;
    CoplanarTriangle tri = coplanar_triangle(hit.prim, q);
    vec2 t;
    if (!coplanar_tangent(tri, hit.bary, vec2(1.0, 0.0), t)) {
        res.status = res.status_other = COPLANAR_DEGENERATE;
        return res;
    }
    // Which way first: towards a sign change of f at the first exit, else towards smaller |f|.
    float order = 1.0;
    {
        vec3 k0 = cross(q.w, coplanar_world(tri, t));
        CoplanarCondition c0 = coplanar_condition(tri, hit.bary, q, k0, true);
        // The straight line is already a solution (eta = 1, or normal incidence).
        if (c0.valid && c0.towards && c0.sine < 1e-6) {
            res.status = res.status_other = COPLANAR_SOLVED;
            res.prim = hit.prim;
            res.bary = hit.bary;
            res.M = coplanar_position(tri, hit.bary);
            return res;
        }
        uint e;
        float s, tau;
        vec2 xe;
        CoplanarArc arc = coplanar_arc(tri, hit.bary, t);
        if (c0.valid && coplanar_exit(tri, arc, 3u, 0.0, e, s, xe, tau)) {
            CoplanarCondition ce = coplanar_condition(tri, xe, q, vec3(0.0), false);
            bool change = ce.valid && (ce.f < 0.0) != (c0.f < 0.0);
            if (!change && ce.valid && abs(ce.f) > abs(c0.f)) order = -1.0;
        }
    }
    uint first = coplanar_walk_from(q, cs, hit.prim, hit.bary, order * t, res);
    res.status = res.status_other = first;
    if (first != COPLANAR_SOLVED && cs.both_directions) {
        uint second = coplanar_walk_from(q, cs, hit.prim, hit.bary, -order * t, res);
        res.status_other = second;
        if (second == COPLANAR_SOLVED) res.status = second;
    }
    return res;
}

// The start rays traced here and the walk (kernels that trace nothing else).
CoplanarResult coplanar_walk(CoplanarQuery q, CoplanarSettings cs) {
    CoplanarStartRay r;
    Hit hit;
    bool found = false;
    for (uint a = 0u; !found && coplanar_start_ray(q, a, r); ++a)
        found = trace_closest(r.o, r.d, r.tmin, r.tmax, COPLANAR_START_MASK, hit);
    return coplanar_walk_from_start(q, cs, found, hit);
}

// Focusing factor D of Eq. 26-33 by ray differentials (Igehy 1999): the beam leaves the light
// (a point: unit angular differentials; a directional light: unit positional ones), is
// transferred to M's triangle plane, scattered with the interpolated normal's derivative, and
// transferred to P; D = |dP_perp,1 x dP_perp,2|, the beam's cross-section at P per unit solid
// angle (per unit area for a directional light). Flat interface, eta = 1: D = (d_L + d_P)^2.
float coplanar_focusing(CoplanarTriangle tri, vec2 x, CoplanarQuery q) {
    vec3 M = coplanar_position(tri, x);
    vec3 N = coplanar_normal(tri, x);
    float Nl = length(N);
    vec3 n = N / Nl;
    vec3 ng = normalize(cross(tri.e1, tri.e2));
    vec3 d = q.directional ? -q.L : normalize(M - q.L);
    float t1 = q.directional ? 0.0 : length(M - q.L);
    vec3 b1 = normalize(abs(d.x) > 0.9 ? cross(d, vec3(0.0, 1.0, 0.0)) : cross(d, vec3(1.0, 0.0, 0.0)));
    vec3 b2 = cross(d, b1);
    // The scattered direction at M.
    bool from_outside = dot(d, n) < 0.0;
    vec3 h = from_outside ? n : -n;          // against d
    float c = -dot(d, h);
    float eta = from_outside ? 1.0 / tri.eta : tri.eta;  // incident / transmitted index
    float ct = 0.0;
    vec3 r;
    if (tri.reflection) {
        r = d - 2.0 * dot(d, n) * n;
    } else {
        float k2 = 1.0 - eta * eta * (1.0 - c * c);
        if (k2 <= 0.0) return 0.0;
        ct = sqrt(k2);
        r = eta * d + (eta * c - ct) * h;
    }
    vec3 P = q.P;
    float t2 = length(P - M);
    // Gram matrix of (e1, e2) for the barycentric differential of a point in the plane.
    float g11 = dot(tri.e1, tri.e1), g12 = dot(tri.e1, tri.e2), g22 = dot(tri.e2, tri.e2);
    float det = g11 * g22 - g12 * g12;
    if (!(det > 0.0) || !(Nl > 0.0)) return 0.0;  // a degenerate triangle
    float inv = 1.0 / det;
    vec3 perp[2];
    for (int i = 0; i < 2; ++i) {
        vec3 bi = i == 0 ? b1 : b2;
        vec3 dp = q.directional ? bi : vec3(0.0);
        vec3 dd = q.directional ? vec3(0.0) : bi;
        // Transfer to the plane of the triangle (Igehy Eq. 10-11).
        dp += t1 * dd;
        dp -= d * (dot(dp, ng) / dot(d, ng));
        // The normal's differential through the barycentrics of dp.
        vec2 rhs = vec2(dot(dp, tri.e1), dot(dp, tri.e2));
        vec2 db = inv * vec2(g22 * rhs.x - g12 * rhs.y, g11 * rhs.y - g12 * rhs.x);
        vec3 dN = db.x * tri.dn1 + db.y * tri.dn2;
        vec3 dn = (dN - n * dot(n, dN)) / Nl;
#ifdef COPLANAR_TEST_FOCUSING_WITHOUT_DN
        dn = vec3(0.0);  // a deliberate bias for the tests: the normal's variation left out
#endif
        vec3 dr;
        if (tri.reflection) {
            dr = dd - 2.0 * ((dot(dd, n) + dot(d, dn)) * n + dot(d, n) * dn);
        } else {
            vec3 dh = from_outside ? dn : -dn;
            float dc = -(dot(dd, h) + dot(d, dh));
            float dct = eta * eta * c * dc / ct;
            dr = eta * dd + (eta * dc - dct) * h + (eta * c - ct) * dh;
        }
        vec3 dpP = dp + t2 * dr;
        perp[i] = dpP - r * dot(r, dpP);
    }
    return length(cross(perp[0], perp[1]));
}

#endif
