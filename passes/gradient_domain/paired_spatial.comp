#version 460
// Spatial reuse of paired-pixel reservoirs (Wang et al. 2025, Sec. 5.1, 5.3): the pair (p, p+e)
// takes one neighbour pair (q, q+e). The outer shift moves a sample (s, b) of pair q to the
// matching pixel p_b of the new pair (Area ReSTIR's film and lens copy, Jacobian 1; or, under a
// thin lens, primary-hit reconnection with its lens-space Jacobian, Eq. 21-22), the inner shift
// evaluates it at p_{1-b}. The two techniques are combined by defensive pairwise MIS or the
// generalized balance heuristic, with confidences, each target pulled back through the outer
// Jacobian.
// Adaptive reuse (Sec. 5.3): a random neighbour pair rarely resembles an edge pair (one whose two
// pixels differ in normal, depth or albedo), whose gradient is the one that matters; for edge
// pairs up to edgeCandidates random pairs in the radius are checked for one whose pixels both
// match. The choice depends on the G-buffer only, never on the samples.
#include "lib/mis.glsl"
#include "lib/sampling.glsl"
#include "passes/gradient_domain/paired_pixel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer PairsIn {
    PairSettings pair_settings_in;
    PairSlots pairs_in[];
};
layout(std430) writeonly buffer PairsOut {
    PairSettings pair_settings_out;
    PairSlots pairs_out[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(std430) readonly buffer FeaturesIn { PixelFeatures features_in[]; };

// Enums arrive as generated defines: OUTER_SHIFT_COPY / OUTER_SHIFT_PRIMARY_RECONNECT,
// MIS_DEFENSIVE_PAIRWISE / MIS_BALANCE, ABLATION_NONE / ABLATION_DROP_OUTER_JACOBIAN /
// ABLATION_REUSE_ACROSS_SIGNS.
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint round;
    float radius;
    uint adaptiveSpatial;
    uint edgeCandidates;
    float normalThreshold;
    float depthThreshold;
    float albedoThreshold;
    uint outerShift;
    uint mis;
    uint ablation;
} pc;

uint pixel_index(ivec2 q) { return uint(q.y) * pc.frameSize.x + uint(q.x); }

bool alike(PixelFeatures a, PixelFeatures b) {
    return features_alike(a, b, pc.normalThreshold, pc.depthThreshold, pc.albedoThreshold);
}

PixelFeatures features_at(ivec2 q) { return features_in[pixel_index(q)]; }

// The neighbour pair of direction d's pair at p (its pixels' features f0, f1), or false.
bool pick_neighbour_pair(inout Rng rng, ivec2 p, uint d, PixelFeatures f0, PixelFeatures f1,
                         out ivec2 q) {
    bool edge = !alike(f0, f1);
    uint tries = pc.adaptiveSpatial != 0u && edge ? max(pc.edgeCandidates, 1u) : 1u;
    for (uint i = 0u; i < tries; ++i) {
        q = ivec2(vec2(p) + 0.5 + pc.radius * sample_disk_concentric(rng_next2(rng)));
        if (all(equal(q, p)) || !pair_inside(q, d, pc.frameSize)) continue;
        if (alike(f0, features_at(q)) && alike(f1, features_at(pair_pixel(q, d, 1u)))) return true;
    }
    return false;
}

// Per slot: evaluations 4 slot + 0/1 = the neighbour's sample at p_b / p_{1-b}, 4 slot + 2/3 =
// the current sample at q_b / q_{1-b}.
const uint MAX_EVALS = 16u;

// The outer shift of sample s (bit b) from pair `src` to pair `dst` (direction d): the
// evaluation at the destination's base pixel, the sample as the inner shift sees it there, and
// the Jacobian.
bool outer_shift(RestirSettings cfg, PathSample s, uint b, ivec2 src, ivec2 dst, uint d,
                 out PairEval base, out PathSample s_dst, out float J) {
    ivec2 src_b = pair_pixel(src, d, b), dst_b = pair_pixel(dst, d, b);
    s_dst = s;
    J = 1.0;
    base = pair_eval_at(s, primary_in[pixel_index(dst_b)], dst_b, false);
    if (pc.outerShift == OUTER_SHIFT_COPY || cfg.area == 0u) return true;
    // Primary-hit reconnection: x1 of the sample in its own domain kept, the lens point solved
    // for at the destination film position (the film offset copied).
    CameraPose pose = restir_sample_pose(cfg, s, false);
    PrimaryHit src_hit = restir_domain_primary(cfg, s, primary_in[pixel_index(src_b)], src_b, pose);
    PrimaryHit hit;
    bool ok = restir_primary_reconnect(s, src_hit, vec2(src_b) + s.film_lens.xy, pose, false,
                                       vec2(dst_b) + s.film_lens.xy, pose, false, pc.frameSize,
                                       s_dst, hit, J);
    scene_select_frame(false);
    base.s = s_dst;
    base.primary = hit;
    base.keep_primary = 1u;
    return ok;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    uint idx = pixel_index(p);
    PairSettings ps = pair_settings_in;
    RestirSettings cfg = ps.restir;
    if (idx == 0u) pair_settings_out = ps;
    PairSlots cur = pairs_in[idx];
    Rng rng = rng_init(uvec2(p), pc.frameIndex, pc.seed ^ (0x1B873593u * (pc.round + 1u)));
    bool positivization = ps.positivization != 0u;

    ivec2 nq[2];
    bool has_q[2];
    PixelFeatures f0 = features_at(p);
    for (uint d = 0u; d < 2u; ++d)
        has_q[d] = pair_inside(p, d, pc.frameSize) &&
                   pick_neighbour_pair(rng, p, d, f0, features_at(pair_pixel(p, d, 1u)), nq[d]);

    PairEval evals[MAX_EVALS];
    bool run[MAX_EVALS];
    float J_here[4], J_there[4];  // the outer shifts' lens Jacobians (primary-hit reconnection)
    PairReservoir nb[4];
    for (uint i = 0u; i < MAX_EVALS; ++i) run[i] = false;
    for (uint slot = 0u; slot < 4u; ++slot) {
        uint d = slot >> 1, sign = slot & 1u;
        J_here[slot] = 0.0;
        J_there[slot] = 0.0;
        nb[slot] = pair_empty();
        if (sign >= pair_signs(ps) || !has_q[d]) continue;
        // Ablation: the neighbour's reservoir of the other sign (reuse across signs).
        uint src_slot = pc.ablation == ABLATION_REUSE_ACROSS_SIGNS && positivization ? slot ^ 1u : slot;
        nb[slot] = pairs_in[pixel_index(nq[d])].slot[src_slot];
        PairReservoir rc = cur.slot[slot];
        PathSample s_dst;
        PairEval base;
        float J;
        if (nb[slot].W > 0.0 && outer_shift(cfg, nb[slot].s, nb[slot].b, nq[d], p, d, base, s_dst, J)) {
            ivec2 partner = pair_pixel(p, d, 1u - nb[slot].b);
            evals[4u * slot] = base;
            evals[4u * slot + 1u] = pair_eval_at(s_dst, primary_in[pixel_index(partner)], partner, false);
            run[4u * slot] = run[4u * slot + 1u] = true;
            J_here[slot] = J;
            nb[slot].s = s_dst;  // as it is here (its lens sample, under reconnection)
        }
        if (rc.W > 0.0 && outer_shift(cfg, rc.s, rc.b, p, nq[d], d, base, s_dst, J)) {
            ivec2 partner = pair_pixel(nq[d], d, 1u - rc.b);
            evals[4u * slot + 2u] = base;
            evals[4u * slot + 3u] = pair_eval_at(s_dst, primary_in[pixel_index(partner)], partner, false);
            run[4u * slot + 2u] = run[4u * slot + 3u] = true;
            J_there[slot] = J;
        }
    }

    vec3 F[MAX_EVALS];
    float solid[MAX_EVALS];
    for (uint i = 0u; i < MAX_EVALS; ++i) {
        F[i] = vec3(0.0);
        solid[i] = 1.0;
        if (!run[i] || ((i & 1u) == 1u && !(luminance(F[i - 1u]) > 0.0))) continue;
        F[i] = pair_eval(ps, evals[i], solid[i]);
    }

    // The outer shift's Jacobian: the lens Jacobian times, in the solid-angle measure,
    // solid_src / solid_dst; targets in another domain are pulled back through it (Lin et al.
    // Eq. 9). The ablation leaves it out.
    bool drop_J = pc.ablation == ABLATION_DROP_OUTER_JACOBIAN;
    // Defensive pairwise MIS (Bitterli 2022; ReSTIRPTSpatial's default) with one neighbour: the
    // neighbour's balance weight halved, the current sample keeps (1 + its balance weight) / 2.
    bool defensive = pc.mis == MIS_DEFENSIVE_PAIRWISE;
    float mis_share = defensive ? 0.5 : 1.0;
    PairSlots out_slots = cur;
    for (uint slot = 0u; slot < 4u; ++slot) {
        uint d = slot >> 1, sign = slot & 1u;
        if (sign >= pair_signs(ps) || !has_q[d]) continue;
        PairReservoir rc = cur.slot[slot], rq = nb[slot];
        PairStream st = pair_stream_begin();
        if (rq.W > 0.0 && J_here[slot] > 0.0) {
            uint e = 4u * slot;
            vec3 g = pair_integrand(F[e], F[e + 1u], rq.b, solid[e]);
            float t_here = pair_target(g, sign, positivization);
            float J = drop_J ? 1.0 : J_here[slot] * rq.solid / solid[e];
            float m = mis_balance2(rq.M, rq.target / J, rc.M, t_here) * mis_share;
            pair_stream_add(st, rq.s, g, t_here, m * t_here * rq.W * J, rng_next(rng), rq.b, solid[e]);
        }
        float t_there = 0.0;
        if (rc.W > 0.0) {
            uint e = 4u * slot + 2u;
            float J = drop_J ? 1.0 : J_there[slot] * rc.solid / solid[e];
            t_there = pair_target(pair_integrand(F[e], F[e + 1u], rc.b, solid[e]), sign,
                                  positivization) * J;
        }
        float m_c = mis_balance2(rc.M, rc.target, rq.M, t_there);
        if (defensive) m_c = 0.5 * (1.0 + m_c);
        pair_stream_add(st, rc.s, rc.g, rc.target, m_c * rc.target * rc.W, rng_next(rng), rc.b,
                        rc.solid);
        out_slots.slot[slot] = pair_stream_end(st, rc.M + rq.M);
    }
    pairs_out[idx] = out_slots;
}
