#version 460
// ReSTIR PT spatial reuse (Lin et al. 2022, Sec. 7): `neighbours` random pixels within `radius`,
// each neighbour's path shifted here, combined with the canonical reservoir by defensive
// pairwise MIS (path_reuse.glsl): the canonical weight starts at 1, gains 1 - (neighbour's share
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
} pc;

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
    PathReservoir r = reservoir_empty();
    float m_c = 1.0;
    float M = rc.M;
    uint valid = 0u;
    for (uint i = 0u; i < pc.neighbours; ++i) {
        ivec2 q = ivec2(vec2(pixel) + 0.5 + pc.radius * sample_disk_concentric(rng_next2(rng)));
        if (all(equal(q, ivec2(pixel))) || any(lessThan(q, ivec2(0))) ||
            any(greaterThanEqual(q, ivec2(pc.frameSize))))
            continue;
        uint qi = uint(q.y) * pc.frameSize.x + uint(q.x);
        PrimaryHit hq = primary_in[qi];
        if (!restir_similar(hc, hq, pc.normalThreshold, pc.depthThreshold)) continue;
        ++valid;
        PathReservoir rq = reservoirs_in[qi];
        CameraPose pose = scene_info.camera_open;
        vec3 F_qc = rq.W > 0.0
            ? restir_shift(cfg, rq.s, restir_domain_primary(cfg, rq.s, hc, ivec2(pixel), pose))
            : vec3(0.0);
        vec3 F_cq = rc.W > 0.0
            ? restir_shift(cfg, rc.s, restir_domain_primary(cfg, rc.s, hq, q, pose))
            : vec3(0.0);
        float t_qc = luminance(F_qc), t_cq = luminance(F_cq);
        // Pair (canonical, q): q's share of its own shifted sample, and of the canonical one.
        float m_q = pairwise_neighbour_weight(rq.M, rq.target, rc.M, t_qc);
        m_c += pairwise_canonical_term(rq.M, t_cq, rc.M, rc.target);
        reservoir_add(r, rq.s, F_qc, t_qc, m_q * t_qc * rq.W, rng_next(rng));
        M += rq.M;
    }
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));
    r.w_sum /= float(valid + 1u);
    r.M = M;
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
}
