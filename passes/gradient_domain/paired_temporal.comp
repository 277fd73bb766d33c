#version 460
// Temporal reuse of paired-pixel reservoirs (Wang et al. 2025, Sec. 5.1) with Area ReSTIR's
// fractional motion vectors (Zhang et al. 2024, Sec. 5; AREA_REPROJECTION_FAST of
// ReSTIRPTTemporal). The pair (p, p + e) moves by the motion vector of its nearer pixel, t; its
// footprint [p, p + 1)^2 + t in the previous film overlaps up to four previous pairs q, each a
// technique covering the part of the current pair's domain its samples translate into: a
// previous sample (s, b) with film offset o in pixel q_b lands at q_b + o - t, which must lie in
// p_b. The outer shift moves s to p_b (film translation, Jacobian 1), the inner shift evaluates
// it at p_{1-b}. The reservoirs of one sign class only take samples of that class. The winner
// of RIS over the previous pairs by their own targets is shifted here and combined with the
// current reservoir by the two-technique generalized balance heuristic; the current sample's
// partner is the previous pair its film position maps to.
#include "lib/mis.glsl"
#include "lib/restir/temporal.glsl"
#include "passes/gradient_domain/paired_pixel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer PairsIn {
    PairSettings pair_settings_in;
    PairSlots pairs_in[];
};
layout(std430) readonly buffer PrevPairs {
    PairSettings pair_settings_prev;
    PairSlots pairs_prev[];
};
layout(std430) writeonly buffer PairsOut {
    PairSettings pair_settings_out;
    PairSlots pairs_out[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(std430) readonly buffer PrevPrimary { PrimaryHit primary_prev[]; };
layout(std430) readonly buffer FeaturesIn { PixelFeatures features_in[]; };
layout(std430) readonly buffer PrevFeatures { PixelFeatures features_prev[]; };
layout(rg32f) uniform readonly image2D motionImage;

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint historyReset;
    float confidenceCap;
    float normalThreshold;
    float depthThreshold;
    float albedoThreshold;
} pc;

uint pixel_index(ivec2 q) { return uint(q.y) * pc.frameSize.x + uint(q.x); }

bool alike(PixelFeatures a, PixelFeatures b) {
    return features_alike(a, b, pc.normalThreshold, pc.depthThreshold, pc.albedoThreshold);
}

// Per slot: evaluations 4 slot + 0/1 = the previous winner at p_b / p_{1-b}, 4 slot + 2/3 = the
// current sample at its previous partner's q_b / q_{1-b}.
const uint MAX_EVALS = 16u;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    uint idx = pixel_index(p);
    PairSettings ps = pair_settings_in;
    RestirSettings cfg = ps.restir;
    if (idx == 0u) pair_settings_out = ps;
    PairSlots cur = pairs_in[idx];
    bool same_rules = restir_same_rules(pair_settings_prev.restir, cfg) &&
                      pair_settings_prev.positivization == ps.positivization &&
                      pair_settings_prev.measure == ps.measure;
    if (pc.historyReset != 0u || !same_rules) {
        pairs_out[idx] = cur;
        return;
    }
    Rng rng = rng_init(uvec2(p), pc.frameIndex, pc.seed ^ 0x61C88647u);
    bool positivization = ps.positivization != 0u;

    PairEval evals[MAX_EVALS];
    bool run[MAX_EVALS];
    for (uint i = 0u; i < MAX_EVALS; ++i) run[i] = false;
    PairReservoir hist[4];  // the previous winner (W over the footprint), film offset translated
    float hist_M[4], M_prev[4], partner_M[4];
    bool partner_ok[4];
    // The current pixels' features: p, p + e_x, p + e_y.
    PixelFeatures here[3];
    here[0] = features_in[idx];
    for (uint d = 0u; d < 2u; ++d)
        if (pair_inside(p, d, pc.frameSize))
            here[1u + d] = features_in[pixel_index(pair_pixel(p, d, 1u))];
    // Per direction: the motion and the usable previous pairs (the same for both signs).
    vec2 motion[2];
    ivec2 block[2];
    uint usable[2];  // bit i: previous pair block + (i & 1, i >> 1) is a technique
    bool area = cfg.area != 0u;
    for (uint d = 0u; d < 2u; ++d) {
        usable[d] = 0u;
        block[d] = ivec2(0);
        motion[d] = vec2(0.0);
        if (!pair_inside(p, d, pc.frameSize)) continue;
        // The pair's motion: that of its nearer pixel.
        PixelFeatures f0 = here[0], f1 = here[1u + d];
        bool first_nearer = f0.valid != 0u && (f1.valid == 0u || f0.depth <= f1.depth);
        motion[d] = imageLoad(motionImage, first_nearer ? p : pair_pixel(p, d, 1u)).xy;
        // Area ReSTIR: the footprint's 2x2 previous pairs. ReSTIR PT (samples start at the
        // pixel's primary hit): the one previous pair at the rounded motion vector.
        block[d] = ivec2(floor(area ? vec2(p) + motion[d] : vec2(p) + 0.5 + motion[d]));
        for (uint i = 0u; i < (area ? 4u : 1u); ++i) {
            ivec2 q = block[d] + ivec2(i & 1u, i >> 1);
            // A previous pair is a technique when both its pixels look like the current pair's.
            if (!pair_inside(q, d, pc.frameSize) ||
                !alike(f0, features_prev[pixel_index(q)]) ||
                !alike(f1, features_prev[pixel_index(pair_pixel(q, d, 1u))]))
                continue;
            usable[d] |= 1u << i;
        }
    }
    for (uint slot = 0u; slot < 4u; ++slot) {
        uint d = slot >> 1, sign = slot & 1u;
        hist[slot] = pair_empty();
        hist_M[slot] = 0.0;
        M_prev[slot] = 0.0;
        partner_ok[slot] = false;
        partner_M[slot] = 0.0;
        if (sign >= pair_signs(ps) || !pair_inside(p, d, pc.frameSize)) continue;
        PairReservoir rc = cur.slot[slot];
        float cap = pc.confidenceCap * rc.M;
        vec2 t = motion[d];
        ivec2 q0 = block[d];
        vec2 f = area ? vec2(p) + t - vec2(q0) : vec2(0.0);
        // The current sample's partner: the previous pair its film position maps to (the same
        // for either bit: both pixels of a pair move by t).
        vec2 Xc = area ? vec2(p) + rc.s.film_lens.xy + t : vec2(q0) + rc.s.film_lens.xy;
        ivec2 qc = ivec2(floor(Xc));
        PairStream frac = pair_stream_begin();
        for (uint i = 0u; i < (area ? 4u : 1u); ++i) {
            ivec2 q = q0 + ivec2(i & 1u, i >> 1);
            if ((usable[d] & (1u << i)) == 0u) continue;
            PairReservoir rq = pairs_prev[pixel_index(q)].slot[slot];
            float Mq = min(rq.M, cap);
            vec2 cover = mix(1.0 - f, f, vec2(i & 1u, i >> 1));
            M_prev[slot] += cover.x * cover.y * Mq;
            if (all(equal(q, qc))) {
                partner_ok[slot] = true;
                partner_M[slot] = Mq;
            }
            vec2 X = area ? vec2(q) + rq.s.film_lens.xy - t : vec2(p) + rq.s.film_lens.xy;
            if (!(rq.W > 0.0) || any(lessThan(X, vec2(p))) || any(greaterThanEqual(X, vec2(p) + 1.0)))
                continue;
            // Parts are disjoint: resampling weight target * W (Area ReSTIR, fast variant).
            PathSample sq = rq.s;
            sq.film_lens.xy = X - vec2(p);
            if (pair_stream_add(frac, sq, rq.g, rq.target, rq.target * rq.W, rng_next(rng), rq.b,
                                rq.solid))
                hist_M[slot] = Mq;
        }
        if (frac.r.w_sum > 0.0) {
            hist[slot] = pair_stream_end(frac, 0.0);
            uint b = hist[slot].b;
            bool moved = restir_crosses_moved_suffix(hist[slot].s, true);
            for (uint e = 0u; e < 2u; ++e) {
                ivec2 dst = pair_pixel(p, d, e == 0u ? b : 1u - b);
                evals[4u * slot + e] = pair_eval_at(hist[slot].s, primary_in[pixel_index(dst)], dst, false);
                run[4u * slot + e] = !moved;
            }
        }
        if (partner_ok[slot] && rc.W > 0.0) {
            uint b = rc.b;
            PathSample s = rc.s;
            s.film_lens.xy = Xc - vec2(qc);
            bool moved = restir_crosses_moved_suffix(rc.s, true);
            for (uint e = 0u; e < 2u; ++e) {
                ivec2 dst = pair_pixel(qc, d, e == 0u ? b : 1u - b);
                evals[4u * slot + 2u + e] = pair_eval_at(s, primary_prev[pixel_index(dst)], dst, true);
                run[4u * slot + 2u + e] = !moved;
            }
        }
    }

    vec3 F[MAX_EVALS];
    float solid[MAX_EVALS];
    for (uint i = 0u; i < MAX_EVALS; ++i) {
        F[i] = vec3(0.0);
        solid[i] = 1.0;
        // The partner evaluation only matters where the base one succeeded.
        if (!run[i] || ((i & 1u) == 1u && !(luminance(F[i - 1u]) > 0.0))) continue;
        F[i] = pair_eval(ps, evals[i], solid[i]);
    }

    // The outer shift's Jacobian: 1 in the mixed measure, solid_src / solid_dst in the
    // solid-angle one; targets in another domain are pulled back through it (Lin et al. Eq. 9).
    PairSlots out_slots = cur;
    for (uint slot = 0u; slot < 4u; ++slot) {
        uint d = slot >> 1, sign = slot & 1u;
        if (sign >= pair_signs(ps) || !pair_inside(p, d, pc.frameSize)) continue;
        PairReservoir rc = cur.slot[slot];
        float Mc = rc.M;
        PairStream st = pair_stream_begin();
        PairReservoir h = hist[slot];
        if (h.W > 0.0) {
            uint e = 4u * slot;
            vec3 g = pair_integrand(F[e], F[e + 1u], h.b, solid[e]);
            float t_here = pair_target(g, sign, positivization);
            float J = h.solid / solid[e];
            float m = mis_balance2(hist_M[slot], h.target / J, Mc, t_here);
            pair_stream_add(st, h.s, g, t_here, m * t_here * h.W * J, rng_next(rng), h.b, solid[e]);
        }
        float t_partner = 0.0;
        if (partner_ok[slot] && rc.W > 0.0) {
            uint e = 4u * slot + 2u;
            t_partner = pair_target(pair_integrand(F[e], F[e + 1u], rc.b, solid[e]), sign,
                                    positivization) * rc.solid / solid[e];
        }
        float m_c = mis_balance2(Mc, rc.target, partner_M[slot], t_partner);
        pair_stream_add(st, rc.s, rc.g, rc.target, m_c * rc.target * rc.W, rng_next(rng), rc.b,
                        rc.solid);
        out_slots.slot[slot] = pair_stream_end(st, Mc + M_prev[slot]);
    }
    pairs_out[idx] = out_slots;
}
