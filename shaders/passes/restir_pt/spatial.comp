#version 460
// ReSTIR PT spatial reuse (Lin et al. 2022, Sec. 7): `neighbours` random pixels within `radius`,
// each neighbour's path shifted here (Area ReSTIR with depth of field: by lens-vertex copy and by
// primary-hit reconnection, Zhang et al. 2024 Sec. 6, each a technique of the MIS), combined
// with the canonical reservoir by defensive pairwise MIS (path_reuse.glsl): the canonical weight starts at 1, gains 1 - (neighbour's share
// of Y_c) per valid neighbour, and all weights are divided by (valid neighbours + 1).
#include "lib/restir/path_reuse.glsl"
#include "lib/sampling.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) writeonly buffer ReservoirsOut {
    RestirSettings settings_out;
    PathReservoir reservoirs_out[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint neighbours;
    uint round;
    float radius;
    float normalThreshold;
    float depthThreshold;
    uint dofShifts;  // Area ReSTIR under a thin lens: SHIFT_COPY | SHIFT_PRIMARY_RECONNECT bits
    uint mis;        // SPATIAL_MIS_*
} pc;

const uint SPATIAL_MIS_DEFENSIVE_PAIRWISE = 0u;
const uint SPATIAL_MIS_PAIRWISE = 1u;
const uint SPATIAL_MIS_BALANCE = 2u;

const uint SHIFT_COPY = 1u;               // film and lens sample replayed (lens-vertex copy)
const uint SHIFT_PRIMARY_RECONNECT = 2u;  // primary hit kept, lens point solved for

// A random neighbour in the disk of `radius`; false when it is this pixel, off screen, or
// geometrically dissimilar (then it is not a technique at all).
bool pick_neighbour(inout Rng rng, uvec2 pixel, PrimaryHit hc, out ivec2 q) {
    q = ivec2(vec2(pixel) + 0.5 + pc.radius * sample_disk_concentric(rng_next2(rng)));
    if (all(equal(q, ivec2(pixel))) || any(lessThan(q, ivec2(0))) ||
        any(greaterThanEqual(q, ivec2(pc.frameSize))))
        return false;
    return restir_similar(hc, primary_in[uint(q.y) * pc.frameSize.x + uint(q.x)],
                          pc.normalThreshold, pc.depthThreshold);
}

vec3 shift_to(RestirSettings cfg, PathSample s, ivec2 q) {
    PrimaryHit h = primary_in[uint(q.y) * pc.frameSize.x + uint(q.x)];
    return restir_shift(cfg, s, restir_domain_primary(cfg, s, h, q, scene_info.camera_open));
}

// Generalized balance heuristic over all techniques (Lin et al. 2022, Eq. 11 with confidences):
// m_i(x) = M_i p_hat_i(x) / sum_j M_j p_hat_j(x), every sample shifted to every domain
// (k^2 + k shifts; copy shift only).
const uint MAX_NEIGHBOURS = 8u;
PathReservoir spatial_balance(RestirSettings cfg, uvec2 pixel, PathReservoir rc, PrimaryHit hc,
                              inout Rng rng) {
    ivec2 qs[MAX_NEIGHBOURS];
    uint k = 0u;
    for (uint i = 0u; i < min(pc.neighbours, MAX_NEIGHBOURS); ++i) {
        ivec2 q;
        if (pick_neighbour(rng, pixel, hc, q)) qs[k++] = q;
    }
    PathReservoir r = reservoir_empty();
    float M = rc.M;
    // Canonical sample: its targets in every neighbour's domain.
    if (rc.W > 0.0) {
        float den = rc.M * rc.target;
        for (uint j = 0u; j < k; ++j) {
            PathReservoir rj = reservoirs_in[uint(qs[j].y) * pc.frameSize.x + uint(qs[j].x)];
            den += rj.M * luminance(shift_to(cfg, rc.s, qs[j]));
        }
        float m = den > 0.0 ? rc.M * rc.target / den : 0.0;
        reservoir_add(r, rc.s, rc.F, rc.target, m * rc.target * rc.W, rng_next(rng));
    }
    for (uint i = 0u; i < k; ++i) {
        PathReservoir ri = reservoirs_in[uint(qs[i].y) * pc.frameSize.x + uint(qs[i].x)];
        M += ri.M;
        if (ri.W <= 0.0) continue;
        vec3 F = shift_to(cfg, ri.s, ivec2(pixel));
        float t = luminance(F);
        if (t <= 0.0) continue;
        float den = ri.M * ri.target + rc.M * t;
        for (uint j = 0u; j < k; ++j) {
            if (j == i) continue;
            PathReservoir rj = reservoirs_in[uint(qs[j].y) * pc.frameSize.x + uint(qs[j].x)];
            den += rj.M * luminance(shift_to(cfg, ri.s, qs[j]));
        }
        float m = ri.M * ri.target / den;
        reservoir_add(r, ri.s, F, t, m * t * ri.W, rng_next(rng));
    }
    r.M = M;
    reservoir_finalize(r);
    return r;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    RestirSettings cfg = settings_in;
    if (idx == 0u) settings_out = cfg;
    PathReservoir rc = reservoirs_in[idx];
    PrimaryHit hc = primary_in[idx];
    if (!primary_valid(hc)) {
        reservoirs_out[idx] = rc;
        return;
    }
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed ^ (0x5BD1E995u * (pc.round + 1u)));
    if (pc.mis == SPATIAL_MIS_BALANCE) {
        reservoirs_out[idx] = spatial_balance(cfg, pixel, rc, hc, rng);
        return;
    }
    CameraPose pose = scene_info.camera_open;
    // Shift techniques per neighbour: the replayed (copied) film/lens sample, and with Area
    // ReSTIR under a thin lens also primary-hit reconnection; each gets half the confidence.
    uint shifts = SHIFT_COPY;
    if (cfg.area != 0u && pose.up.w > 0.0) shifts = pc.dofShifts;
    float n_shifts = float(bitCount(shifts));
    PathReservoir r = reservoir_empty();
    float m_c = 1.0;
    float M = rc.M;
    uint techniques = 0u;
    for (uint i = 0u; i < pc.neighbours; ++i) {
        ivec2 q;
        if (!pick_neighbour(rng, pixel, hc, q)) continue;
        uint qi = uint(q.y) * pc.frameSize.x + uint(q.x);
        PrimaryHit hq = primary_in[qi];
        PathReservoir rq = reservoirs_in[qi];
        float Mq = rq.M / n_shifts;
        for (uint t = SHIFT_COPY; t <= SHIFT_PRIMARY_RECONNECT; t <<= 1) {
            if ((shifts & t) == 0u) continue;
            ++techniques;
            // The neighbour's sample shifted here, and the canonical sample shifted there.
            PathSample s_qc = rq.s;
            vec3 F_qc = vec3(0.0), F_cq = vec3(0.0);
            float J_qc = 1.0, J_cq = 1.0;
            if (t == SHIFT_COPY) {
                if (rq.W > 0.0)
                    F_qc = restir_shift(cfg, rq.s, restir_domain_primary(cfg, rq.s, hc, ivec2(pixel), pose));
                if (rc.W > 0.0)
                    F_cq = restir_shift(cfg, rc.s, restir_domain_primary(cfg, rc.s, hq, q, pose));
            } else {
                PathSample s_tmp;
                PrimaryHit dst;
                if (rq.W > 0.0 &&
                    restir_primary_reconnect(rq.s, restir_domain_primary(cfg, rq.s, hq, q, pose), q,
                                             pose, ivec2(pixel), pose, pc.frameSize, s_qc, dst, J_qc))
                    F_qc = restir_shift(cfg, s_qc, dst);
                if (rc.W > 0.0 &&
                    restir_primary_reconnect(rc.s, restir_domain_primary(cfg, rc.s, hc, ivec2(pixel), pose),
                                             ivec2(pixel), pose, q, pose, pc.frameSize, s_tmp, dst, J_cq))
                    F_cq = restir_shift(cfg, s_tmp, dst);
            }
            float t_qc = luminance(F_qc), t_cq = luminance(F_cq) * J_cq;
            // Pair (canonical, q, shift t); targets carry the shift's Jacobian (GRIS, Lin et al.
            // Eq. 9): p_hat_q seen from here is p_hat_q(x_q) / J_qc.
            float m_q = pairwise_neighbour_weight(Mq, J_qc > 0.0 ? rq.target / J_qc : 0.0, rc.M, t_qc);
            m_c += pairwise_canonical_term(Mq, t_cq, rc.M, rc.target);
            reservoir_add(r, s_qc, F_qc, t_qc, m_q * t_qc * rq.W * J_qc, rng_next(rng));
            M += Mq;
        }
    }
    // Defensive: the canonical technique keeps a share 1 / (k + 1); non-defensive pairwise
    // divides by k and the canonical weight has no extra 1 (all its weight with no neighbour).
    bool defensive = pc.mis == SPATIAL_MIS_DEFENSIVE_PAIRWISE || techniques == 0u;
    if (!defensive) m_c -= 1.0;
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));
    r.w_sum /= float(defensive ? techniques + 1u : techniques);
    r.M = M;
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
}
