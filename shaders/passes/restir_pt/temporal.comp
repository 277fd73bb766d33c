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
    uint areaVariant;        // Area ReSTIR reprojection: AREA_FAST, AREA_ROBUST, AREA_COPY
    float confidenceCap;
    float normalThreshold;
    float depthThreshold;
} pc;

// Area ReSTIR temporal reprojection (Zhang et al. 2024, Sec. 5). Samples carry film positions, so
// the previous frame's samples are translated by this pixel's fractional motion vector t (a
// bijection with Jacobian 1). The current pixel's footprint in the previous film, [p, p+1)^2 + t,
// overlaps up to four previous pixels whose parts are disjoint: each previous pixel is a
// technique covering only its part.
const uint AREA_FAST = 0u;    // RIS over the 2x2 block by previous targets, shift the winner
const uint AREA_ROBUST = 1u;  // shift all four first, resample by current targets
const uint AREA_COPY = 2u;    // one previous pixel, subpixel offset copied (no fraction)

PathSample with_film_offset(PathSample s, vec2 offset) {
    s.film_lens.xy = offset;
    return s;
}

bool prev_pixel_usable(ivec2 q, PrimaryHit hc) {
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.frameSize)))) return false;
    return restir_similar(hc, primary_prev[uint(q.y) * pc.frameSize.x + uint(q.x)],
                          pc.normalThreshold, pc.depthThreshold);
}

PathReservoir area_temporal(RestirSettings cfg, uvec2 pixel, PathReservoir rc, PrimaryHit hc) {
    vec2 t = imageLoad(motionImage, ivec2(pixel)).xy;
    vec2 base = vec2(pixel) + t;  // footprint origin in the previous film
    ivec2 q0 = ivec2(floor(base));
    vec2 frac_ = base - vec2(q0);
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x7E3A1F55u);
    PathReservoir r = reservoir_empty();
    float Mc = rc.M;
    float cap = pc.confidenceCap * rc.M;

    // The canonical sample's technique partner: the previous pixel its film position maps to.
    vec2 Xc = vec2(pixel) + rc.s.film_lens.xy + t;
    ivec2 qc = ivec2(floor(Xc));
    float t_cp = 0.0, M_qc = 0.0;
    if (rc.W > 0.0 && prev_pixel_usable(qc, hc)) {
        uint qi = uint(qc.y) * pc.frameSize.x + uint(qc.x);
        M_qc = min(reservoirs_prev[qi].M, cap);
        PathSample sc = with_film_offset(rc.s, Xc - vec2(qc));
        t_cp = luminance(restir_shift(cfg, sc, restir_domain_primary(cfg, sc, primary_prev[qi], qc,
                                                                      scene_info.camera_prev)));
    }

    PathReservoir frac_r = reservoir_empty();  // AREA_FAST: the fractional reservoir
    uint frac_q = 0u;
    float M_prev = 0.0;
    for (uint i = 0u; i < 4u; ++i) {
        ivec2 q = q0 + ivec2(i & 1u, i >> 1);
        if (!prev_pixel_usable(q, hc)) continue;
        uint qi = uint(q.y) * pc.frameSize.x + uint(q.x);
        PathReservoir rq = reservoirs_prev[qi];
        float Mq = min(rq.M, cap);
        // Bilinear share of the footprint this pixel covers, for the confidence.
        vec2 cover = mix(1.0 - frac_, frac_, vec2(i & 1u, i >> 1));
        M_prev += cover.x * cover.y * Mq;
        // Its sample lands in this pixel only from its part of the footprint.
        vec2 X = vec2(q) + rq.s.film_lens.xy - t;
        if (rq.W <= 0.0 || any(lessThan(X, vec2(pixel))) || any(greaterThanEqual(X, vec2(pixel) + 1.0)))
            continue;
        PathSample sq = with_film_offset(rq.s, X - vec2(pixel));
        if (pc.areaVariant == AREA_FAST) {
            // Resample by the previous targets (no shift yet); parts are disjoint: weight 1.
            if (reservoir_add(frac_r, sq, vec3(0.0), rq.target, rq.target * rq.W, rng_next(rng))) {
                frac_q = i;
                frac_r.M = Mq;  // confidence of the winner's technique, for its MIS weight
            }
            continue;
        }
        vec3 F = restir_shift(cfg, sq, restir_domain_primary(cfg, sq, hc, ivec2(pixel), scene_info.camera_open));
        float t_qc = luminance(F);
        float m_q = mis_balance2(Mq, rq.target, Mc, t_qc);
        reservoir_add(r, sq, F, t_qc, m_q * t_qc * rq.W, rng_next(rng));
    }
    if (pc.areaVariant == AREA_FAST && frac_r.w_sum > 0.0) {
        float Mq = frac_r.M;
        float t_prev = frac_r.target;
        float W_frac = frac_r.w_sum / t_prev;
        vec3 F = restir_shift(cfg, frac_r.s, restir_domain_primary(cfg, frac_r.s, hc, ivec2(pixel),
                                                                      scene_info.camera_open));
        float t_qc = luminance(F);
        float m_q = mis_balance2(Mq, t_prev, Mc, t_qc);
        reservoir_add(r, frac_r.s, F, t_qc, m_q * t_qc * W_frac, rng_next(rng));
    }
    float m_c = mis_balance2(Mc, rc.target, M_qc, t_cp);
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));
    r.M = Mc + M_prev;
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
    if (pc.historyValid == 0u || !primary_valid(hc)) {
        reservoirs_out[idx] = rc;
        return;
    }
    if (cfg.area != 0u && pc.areaVariant != AREA_COPY) {
        reservoirs_out[idx] = area_temporal(cfg, pixel, rc, hc);
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
