// Paired-pixel reservoirs of gradient-domain ReSTIR PT (Wang et al. 2025, Sec. 4-5), shared by
// paired_initial/temporal/spatial/resolve.comp.
//
// The pair (p, p + e) for e = e_x or e_y owns the paired-pixel domain X = Omega_p x {0} u
// Omega_{p+e} x {1}: a path sample s with the bit b of the pixel whose domain it lies in (its
// base pixel; the other is its partner). With F_q(s) the integrand of s at pixel q (hybrid shift
// from anywhere; Jacobian 1 in the mixed measure of reservoir.glsl), the pair integrand is
//   g(s, b) = w*(s, b) G(s, b),  G = F_{p+e}(s) - F_p(s)  (forward difference, the solvers' sign;
//   the paper's Delta_ij is the opposite),  w* = p(F_base) / (p(F_base) + p(F_partner))
// (Eq. 13-16, p = luminance). The two bits' w* sum to 1 wherever the inner shift is defined, so
// the integral of g over X is I(p + e) - I(p). Reservoirs resample g with target |g|
// (luminance of |g| per channel) or, with positivization, one reservoir per sign class of
// luminance(g), never mixed (Sec. 5.2).
#ifndef LOOM_PAIRED_PIXEL_GLSL
#define LOOM_PAIRED_PIXEL_GLSL

#include "lib/color.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/primary.glsl"
#include "lib/restir/primary_shift.glsl"
#include "lib/restir/reservoir.glsl"

// Settings written by PairedPixelInitial, carried with the pair reservoirs.
struct PairSettings {
    RestirSettings restir;  // the path samples' rules (Area ReSTIR's initial pass)
    uint positivization;    // 1: separate reservoirs for g >= 0 and g < 0
    uint measure;           // PAIR_MEASURE_*
};

// The measure of the pair integrand. Mixed: reservoir.glsl's (area at the reconnection vertex
// x_k), in which the hybrid shift's Jacobian is 1. Solid angle at x_{k-1} (the paper's, after Lin
// et al.): g and the targets carry the factor d^2 / |cos| of the sample's segment to x_k at its
// base pixel, and a shift from base pixel a to c has the Jacobian factor solid_a / solid_c
// (Lin et al. Eq. 17). Both give the same estimator; only the second can lose a Jacobian.
const uint PAIR_MEASURE_MIXED = 0u;
const uint PAIR_MEASURE_SOLID_ANGLE = 1u;

// A pair reservoir (same size as PathReservoir).
struct PairReservoir {
    PathSample s;
    vec3 g;        // the pair integrand of s at this pair (signed RGB, in the pair measure)
    float W;       // unbiased contribution weight: gradient estimate g W
    float M;       // confidence
    float target;  // pair_target of g in the slot's sign class
    uint b;        // the sample's base pixel in the pair (0: p, 1: p + e)
    float solid;   // solid-angle measure: d^2 / |cos| at x_k of s at its base pixel; else 1
};

// Four pair reservoirs per pixel p: slot 2 d + sign for the pair (p, p + kPairOffsets[d]).
struct PairSlots {
    PairReservoir slot[4];
};

PairReservoir pair_empty() {
    PairReservoir r;
    r.s = reservoir_empty().s;
    r.g = vec3(0.0);
    r.W = 0.0;
    r.M = 0.0;
    r.target = 0.0;
    r.b = 0u;
    r.solid = 1.0;
    return r;
}

// Streaming RIS into a pair reservoir: reservoir.glsl's, keeping the winner's pair fields.
struct PairStream {
    PathReservoir r;
    uint b;
    float solid;
};

PairStream pair_stream_begin() {
    PairStream st;
    st.r = reservoir_empty();
    st.b = 0u;
    st.solid = 1.0;
    return st;
}

bool pair_stream_add(inout PairStream st, PathSample s, vec3 g, float target, float w, float u,
                     uint b, float solid) {
    if (!reservoir_add(st.r, s, g, target, w, u)) return false;
    st.b = b;
    st.solid = solid;
    return true;
}

PairReservoir pair_stream_end(PairStream st, float M) {
    reservoir_finalize(st.r);
    PairReservoir r;
    r.s = st.r.s;
    r.g = st.r.F;
    r.W = st.r.W;
    r.M = M;
    r.target = st.r.W > 0.0 ? st.r.target : 0.0;
    r.b = st.b;
    r.solid = st.solid;
    return r;
}

const ivec2 kPairOffsets[2] = ivec2[2](ivec2(1, 0), ivec2(0, 1));
const uint PAIR_POSITIVE = 0u;  // luminance(g) >= 0 (also: every sign, without positivization)
const uint PAIR_NEGATIVE = 1u;

uint pair_slot(uint d, uint sign) { return 2u * d + sign; }
uint pair_signs(PairSettings ps) { return ps.positivization != 0u ? 2u : 1u; }

bool pair_inside(ivec2 p, uint d, uvec2 frame_size) {
    ivec2 q = p + kPairOffsets[d];
    return all(greaterThanEqual(p, ivec2(0))) && all(lessThan(q, ivec2(frame_size)));
}

// Pixel b of the pair at p in direction d.
ivec2 pair_pixel(ivec2 p, uint d, uint b) { return p + int(b) * kPairOffsets[d]; }

// g(s, b) from the sample's integrands (mixed measure) at its base pixel and at its partner and
// its measure factor at the base pixel; 0 outside the pair's domain (the sample does not shift
// to its base pixel). w* and G in the solid-angle measure: the partner's factor cancels against
// the inner shift's Jacobian, the base pixel's remains.
vec3 pair_integrand(vec3 F_base, vec3 F_partner, uint b, float solid_base) {
    float t = luminance(F_base), t_partner = luminance(F_partner);
    if (!(t > 0.0)) return vec3(0.0);
    float w = t / (t + t_partner);
    return solid_base * w * (b == 0u ? F_partner - F_base : F_base - F_partner);
}

float pair_target(vec3 g, uint sign, bool positivization) {
    bool positive = luminance(g) >= 0.0;
    if (positivization && positive != (sign == PAIR_POSITIVE)) return 0.0;
    return luminance(abs(g));
}

// Evaluating a path sample at a pixel: every kernel runs its list of these through one call of
// pair_eval (lavapipe compiles each inlined copy of the shift and its traversals separately).
struct PairEval {
    PathSample s;         // film offset and lens sample already those of the destination
    PrimaryHit primary;   // the pixel's primary hit (ReSTIR PT), or the fixed x1 (keep_primary)
    ivec2 pixel;
    uint previous;        // evaluate in the previous frame (camera and geometry)
    uint keep_primary;    // primary-hit reconnection: x1 and the lens point are given
};

PairEval pair_eval_at(PathSample s, PrimaryHit primary, ivec2 pixel, bool previous) {
    PairEval e;
    e.s = s;
    e.primary = primary;
    e.pixel = pixel;
    e.previous = previous ? 1u : 0u;
    e.keep_primary = 0u;
    return e;
}

// The integrand (mixed measure) and, in the solid-angle measure, the sample's factor solid there.
vec3 pair_eval(PairSettings ps, PairEval e, out float solid) {
    RestirSettings cfg = ps.restir;
    scene_select_frame(e.previous != 0u);
    PrimaryHit dst = e.primary;
    if (e.keep_primary == 0u)
        dst = restir_domain_primary(cfg, e.s, e.primary, e.pixel,
                                    restir_sample_pose(cfg, e.s, e.previous != 0u));
    ShiftDensity sd;
    vec3 F = restir_shift_with_density(cfg, e.s, dst, sd);
    scene_select_frame(false);
    solid = ps.measure == PAIR_MEASURE_SOLID_ANGLE && sd.G_rc > 0.0 ? 1.0 / sd.G_rc : 1.0;
    return F;
}

// What the G-buffer tests of gradient reuse compare of a primary hit (computed once per pixel:
// the edge-pair search compares hundreds of candidates).
struct PixelFeatures {
    vec3 n;        // shading normal (before normal mapping)
    float depth;   // camera distance
    vec3 albedo;   // diffuse + specular reflectance
    uint valid;    // 0: a miss
};

PixelFeatures pixel_features(PrimaryHit h, bool previous) {
    PixelFeatures f;
    f.valid = primary_valid(h) ? 1u : 0u;
    f.n = vec3(0.0);
    f.depth = 0.0;
    f.albedo = vec3(0.0);
    if (f.valid == 0u) return f;
    scene_select_frame(previous);
    ShadingPoint sh = restir_primary_shading(h);
    scene_select_frame(false);
    f.n = sh.sp.ns;
    f.depth = length(sh.sp.p - h.camera.xyz);
    f.albedo = sh.mat.diffuse.rgb + sh.mat.specular.rgb;
    return f;
}

// Whether two pixels look alike for gradient reuse: normals (cosine >= normal_threshold, the
// paper's 0.9), relative camera distance and albedo (max channel difference). Pairs whose two
// pixels are not alike are edge pairs. Two misses are alike.
bool features_alike(PixelFeatures a, PixelFeatures b, float normal_threshold,
                    float depth_threshold, float albedo_threshold) {
    if (a.valid == 0u || b.valid == 0u) return a.valid == b.valid;
    if (dot(a.n, b.n) < normal_threshold) return false;
    if (abs(a.depth - b.depth) > depth_threshold * max(a.depth, b.depth)) return false;
    vec3 diff = abs(a.albedo - b.albedo);
    return max(diff.x, max(diff.y, diff.z)) <= albedo_threshold;
}

#endif
