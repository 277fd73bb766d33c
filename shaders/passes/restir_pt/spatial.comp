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
} pc;

const uint SHIFT_COPY = 1u;               // film and lens sample replayed (lens-vertex copy)
const uint SHIFT_PRIMARY_RECONNECT = 2u;  // primary hit kept, lens point solved for

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
        ivec2 q = ivec2(vec2(pixel) + 0.5 + pc.radius * sample_disk_concentric(rng_next2(rng)));
        if (all(equal(q, ivec2(pixel))) || any(lessThan(q, ivec2(0))) ||
            any(greaterThanEqual(q, ivec2(pc.frameSize))))
            continue;
        uint qi = uint(q.y) * pc.frameSize.x + uint(q.x);
        PrimaryHit hq = primary_in[qi];
        if (!restir_similar(hc, hq, pc.normalThreshold, pc.depthThreshold)) continue;
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
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));
    r.w_sum /= float(techniques + 1u);
    r.M = M;
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
}
