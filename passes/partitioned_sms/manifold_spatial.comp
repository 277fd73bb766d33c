#version 460
// ManifoldReSTIRSpatial (Hong et al. 2025 Sec. 5): `neighbours` random receivers within
// `radius` pixels (paper: 1 in 30 px); each one's sample is shifted here by the manifold shift,
// and this pixel's sample to each of them for the MIS weights. Pairwise MIS (Bitterli 2022
// Sec. 9.1.3) with confidences, with k valid neighbours:
//   m_q(x) = b_q(x) / k,  m_c(x) = sum_q (1 - b_q(x)) / k,
//   b_q(x) = M_q p_q(T^-1 x) / (M_q p_q(T^-1 x) + M_c p_c(x)),
// or its defensive form (every weight over k + 1, the canonical one plus 1). A failed shift is
// a target of 0: the canonical technique keeps what no neighbour covers.
#include "lib/sampling.glsl"
#include "passes/partitioned_sms/manifold_reuse.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint constraint;
    uint shiftIterations;
    float solverThreshold;
    float uniquenessThreshold;
    uint bijectivity;
    float geometricTermClamp;
    uint maxChain;
    float minSegment;
    uint neighbours;
    float radius;
    float normalThreshold;
    float depthThreshold;
    uint mis;  // MIS_PAIRWISE, MIS_DEFENSIVE_PAIRWISE
} pc;

const uint MAX_NEIGHBOURS = 4u;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint index = pixel.y * pc.frameSize.x + pixel.x;
    if (index == 0u) header_out = header_in;
    ManifoldReservoir rc = reservoirs_in[index];
    if (!primary_valid(rc.receiver)) {
        manifold_reuse_finish(pixel, index, rc, 0u, 0u);
        return;
    }
    // Techniques: neighbours chosen by geometry alone (independent of the samples).
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x3C6EF372u);
    uint nq[MAX_NEIGHBOURS];
    uint n = 0u;
    for (uint i = 0u; i < min(pc.neighbours, MAX_NEIGHBOURS); ++i) {
        ivec2 q = ivec2(vec2(pixel) + 0.5 + pc.radius * sample_disk_concentric(rng_next2(rng)));
        if (all(equal(q, ivec2(pixel))) || any(lessThan(q, ivec2(0))) ||
            any(greaterThanEqual(q, ivec2(pc.frameSize))))
            continue;
        uint qi = uint(q.y) * pc.frameSize.x + uint(q.x);
        if (!restir_similar(rc.receiver, reservoirs_in[qi].receiver, false, pc.normalThreshold,
                            pc.depthThreshold))
            continue;
        nq[n++] = qi;
    }
    ManifoldShiftSettings ss = manifold_reuse_settings(
        pc.constraint, pc.shiftIterations, pc.solverThreshold, pc.uniquenessThreshold,
        pc.minSegment, pc.maxChain, pc.geometricTermClamp, pc.bijectivity);
    // Shifts it < n: neighbour it's sample here; it >= n: the canonical sample to neighbour
    // it - n (its target there). One call site (code size).
    ManifoldSample s_here[MAX_NEIGHBOURS];
    vec3 F_here[MAX_NEIGHBOURS];
    float t_c_to[MAX_NEIGHBOURS];
    for (uint i = 0u; i < n; ++i) {
        F_here[i] = vec3(0.0);
        t_c_to[i] = 0.0;
    }
    uint attempts = 0u, success = 0u;
    for (uint it = 0u; it < 2u * n; ++it) {
        bool to_here = it < n;
        uint j = to_here ? it : it - n;
        ManifoldReservoir rq = reservoirs_in[nq[j]];
        ManifoldReservoir src = to_here ? rq : rc;
        if (!(src.weight.x > 0.0)) continue;
        ManifoldSample t;
        vec3 F;
        attempts += 1u;
        if (!manifold_shift(src.s, src.receiver, false, to_here ? rc.receiver : rq.receiver, false,
                            ss, t, F))
            continue;
        success += 1u;
        if (to_here) {
            s_here[j] = t;
            F_here[j] = F;
        } else {
            t_c_to[j] = luminance(F);
        }
    }
    bool defensive = pc.mis == MIS_DEFENSIVE_PAIRWISE;
    float norm = defensive ? 1.0 / float(n + 1u) : 1.0 / float(max(n, 1u));
    float M_c = rc.weight.y, p_c = rc.F.w;
    float m_c = n == 0u ? 1.0 : (defensive ? 1.0 : 0.0);
    for (uint j = 0u; j < n; ++j)
        m_c += p_c > 0.0 ? mis_balance2(M_c, p_c, reservoirs_in[nq[j]].weight.y, t_c_to[j]) : 0.0;
    if (n > 0u) m_c *= norm;
    ManifoldReservoir r = rc;
    float w_sum = 0.0, M = M_c;
    manifold_reservoir_take(w_sum, m_c * p_c * rc.weight.x, rng_next(rng));
    for (uint j = 0u; j < n; ++j) {
        ManifoldReservoir rq = reservoirs_in[nq[j]];
        M += rq.weight.y;
        float p_here = luminance(F_here[j]);
        if (!(p_here > 0.0)) continue;
        float m_q = norm * mis_balance2(rq.weight.y, rq.F.w, M_c, p_here);
        if (manifold_reservoir_take(w_sum, m_q * p_here * rq.weight.x, rng_next(rng))) {
            r.s = s_here[j];
            r.F = vec4(F_here[j], p_here);
        }
    }
    manifold_reservoir_finalize(r, w_sum);
    r.weight.y = M;
    manifold_reuse_finish(pixel, index, r, attempts, success);
}
