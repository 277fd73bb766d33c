#version 460
// ReSTIR PT temporal reuse (Lin et al. 2022, Sec. 7): the previous frame's final reservoir at
// the motion-vector reprojected pixel is shifted into this pixel and combined with the current
// one by the 2-technique generalized balance heuristic (Talbot) with confidences; the history's
// confidence is clamped to confidenceCap times the current one.
#include "lib/restir/path_reuse.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) readonly buffer PrevReservoirs {
    RestirSettings settings_prev;
    PathReservoir reservoirs_prev[];
};
layout(std430) writeonly buffer ReservoirsOut {
    RestirSettings settings_out;
    PathReservoir reservoirs_out[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(std430) readonly buffer PrevPrimary { PrimaryHit primary_prev[]; };
layout(rg32f) uniform readonly image2D motionImage;

const uint TEMPORAL_MIS_BALANCE = 0u;  // generalized balance heuristic (default)
const uint TEMPORAL_MIS_UNIFORM = 1u;  // confidence weights over techniques that can shift

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint historyValid;
    uint mis;
    uint countFailedShifts;  // ablation: reproduces the "failed shift in the denominator" bias
    float confidenceCap;
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
    if (pc.historyValid == 0u || !primary_valid(hc)) {
        reservoirs_out[idx] = rc;
        return;
    }
    vec2 prev = vec2(pixel) + 0.5 + imageLoad(motionImage, ivec2(pixel)).xy;
    ivec2 q = ivec2(floor(prev));
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.frameSize)))) {
        reservoirs_out[idx] = rc;
        return;
    }
    uint qi = uint(q.y) * pc.frameSize.x + uint(q.x);
    PrimaryHit hp = primary_prev[qi];
    if (!restir_similar(hc, hp, pc.normalThreshold, pc.depthThreshold)) {
        reservoirs_out[idx] = rc;
        return;
    }
    PathReservoir rp = reservoirs_prev[qi];
    float Mc = rc.M, Mp = min(rp.M, pc.confidenceCap * rc.M);

    // Y_p shifted here, and the canonical Y_c shifted to the previous pixel (for its weight).
    vec3 F_pc = rp.W > 0.0
        ? restir_shift(cfg, rp.s, restir_domain_primary(cfg, rp.s, hc, ivec2(pixel), scene_info.camera_open))
        : vec3(0.0);
    vec3 F_cp = rc.W > 0.0
        ? restir_shift(cfg, rc.s, restir_domain_primary(cfg, rc.s, hp, q, scene_info.camera_prev))
        : vec3(0.0);
    float t_pc = luminance(F_pc), t_cp = luminance(F_cp);
    float m_c, m_p;
    if (pc.mis == TEMPORAL_MIS_BALANCE) {
        m_c = mis_balance2(Mc, rc.target, Mp, t_cp);
        m_p = mis_balance2(Mp, rp.target, Mc, t_pc);
    } else {
        // 1/|Z(x)| with confidences: only techniques that can produce x count. With
        // countFailedShifts the previous frame is counted even when Y_c cannot shift there.
        bool prev_counts = t_cp > 0.0 || pc.countFailedShifts != 0u;
        m_c = Mc / (Mc + (prev_counts ? Mp : 0.0));
        m_p = Mp / (Mp + Mc);
    }

    PathReservoir r = reservoir_empty();
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x7E3A1F55u);
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));
    reservoir_add(r, rp.s, F_pc, t_pc, m_p * t_pc * rp.W, rng_next(rng));
    r.M = Mc + Mp;
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
}
