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
    uint shapesMoved;  // the scene's shapes moved since the previous frame
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

uint pixel_index(ivec2 q) { return uint(q.y) * pc.frameSize.x + uint(q.x); }

// Shift jobs, all run through one restir_shift call site (lavapipe compiles every inlined copy
// of the shift and its BVH traversals separately: code size is speed). Job 0: the canonical
// sample to its previous-frame partner; jobs 1..: previous samples to this pixel; when shapes
// moved, then each of those previous samples at its own previous pixel.
//
// Moving shapes: only this frame's geometry is on the GPU, so the canonical sample's target in
// the previous domain (job 0) is evaluated in it. The MIS weights stay a partition of unity
// only if the previous samples' own targets come from the same function, so they are evaluated
// again in this geometry instead of using the stored ones (exact for a static scene, where both
// agree and the extra shifts are skipped). What remains approximate is the support: a path that
// exists now but was blocked in the previous frame's geometry still lowers the canonical
// weight.
const uint MAX_PREV_JOBS = 4u;
const uint MAX_JOBS = 1u + 2u * MAX_PREV_JOBS;
struct ShiftJob {
    PathSample s;
    uint prev;        // 1: destination is a previous-frame pixel
    ivec2 q;          // destination pixel
    uint source;      // previous pixel slot of the sample (jobs 1..)
};

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    RestirSettings cfg = settings_in;
    if (idx == 0u) settings_out = cfg;
    PathReservoir rc = reservoirs_in[idx];
    PrimaryHit hc = primary_in[idx];
    // History generated under other path rules (shift, thresholds, bounces) cannot be shifted
    // consistently: drop it (the first frame after a parameter change).
    RestirSettings prev_cfg = settings_prev;
    bool same_rules = prev_cfg.max_bounces == cfg.max_bounces && prev_cfg.shift == cfg.shift &&
                      prev_cfg.rough_threshold == cfg.rough_threshold &&
                      prev_cfg.dist_threshold == cfg.dist_threshold &&
                      all(equal(prev_cfg.frame_size, cfg.frame_size)) &&
                      prev_cfg.mis_heuristic == cfg.mis_heuristic && prev_cfg.area == cfg.area;
    if (pc.historyValid == 0u || !same_rules || !primary_valid(hc)) {
        reservoirs_out[idx] = rc;
        return;
    }
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x7E3A1F55u);
    float Mc = rc.M, cap = pc.confidenceCap * rc.M;
    bool fractional = cfg.area != 0u && pc.areaVariant != AREA_COPY;
    vec2 t = imageLoad(motionImage, ivec2(pixel)).xy;

    // Previous-frame techniques: one pixel (ReSTIR PT, Area copy) or the 2x2 footprint block.
    ivec2 slot_q[4];
    float slot_M[4];
    uint slots = 0u;
    ShiftJob jobs[MAX_JOBS];
    uint n_jobs = 1u;
    jobs[0].prev = 1u;
    jobs[0].source = 0u;
    jobs[0].s = rc.s;
    bool canonical_partner = false;
    float M_prev = 0.0;
    PathReservoir frac_r = reservoir_empty();  // AREA_FAST: the fractional reservoir
    float W_frac = 0.0;
    if (!fractional) {
        ivec2 q = ivec2(floor(vec2(pixel) + 0.5 + t));
        if (prev_pixel_usable(q, hc)) {
            PathReservoir rp = reservoirs_prev[pixel_index(q)];
            slot_q[0] = q;
            slot_M[0] = min(rp.M, cap);
            slots = 1u;
            M_prev = slot_M[0];
            jobs[0].q = q;
            canonical_partner = true;
            if (rp.W > 0.0) {
                jobs[1].s = rp.s;
                jobs[1].prev = 0u;
                jobs[1].q = ivec2(pixel);
                jobs[1].source = 0u;
                n_jobs = 2u;
            }
        }
    } else {
        vec2 base = vec2(pixel) + t;  // footprint origin in the previous film
        ivec2 q0 = ivec2(floor(base));
        vec2 f = base - vec2(q0);
        // The canonical sample's partner: the previous pixel its film position maps to.
        vec2 Xc = vec2(pixel) + rc.s.film_lens.xy + t;
        ivec2 qc = ivec2(floor(Xc));
        for (uint i = 0u; i < 4u; ++i) {
            ivec2 q = q0 + ivec2(i & 1u, i >> 1);
            if (!prev_pixel_usable(q, hc)) continue;
            PathReservoir rq = reservoirs_prev[pixel_index(q)];
            uint sl = slots++;
            slot_q[sl] = q;
            slot_M[sl] = min(rq.M, cap);
            // Bilinear share of the footprint this pixel covers, for the confidence.
            vec2 cover = mix(1.0 - f, f, vec2(i & 1u, i >> 1));
            M_prev += cover.x * cover.y * slot_M[sl];
            if (all(equal(q, qc))) {
                canonical_partner = true;
                jobs[0].q = q;
                jobs[0].source = sl;
                jobs[0].s = with_film_offset(rc.s, Xc - vec2(qc));
            }
            // Its sample lands in this pixel only from its part of the footprint.
            vec2 X = vec2(q) + rq.s.film_lens.xy - t;
            if (rq.W <= 0.0 || any(lessThan(X, vec2(pixel))) || any(greaterThanEqual(X, vec2(pixel) + 1.0)))
                continue;
            PathSample sq = with_film_offset(rq.s, X - vec2(pixel));
            if (pc.areaVariant == AREA_FAST) {
                // Resample by the previous targets (no shift yet); parts are disjoint: weight 1.
                if (reservoir_add(frac_r, sq, vec3(0.0), rq.target, rq.target * rq.W, rng_next(rng)))
                    frac_r.pad = sl;
                continue;
            }
            jobs[n_jobs].s = sq;
            jobs[n_jobs].prev = 0u;
            jobs[n_jobs].q = ivec2(pixel);
            jobs[n_jobs].source = sl;
            ++n_jobs;
        }
        if (pc.areaVariant == AREA_FAST && frac_r.w_sum > 0.0) {
            W_frac = frac_r.w_sum / frac_r.target;
            jobs[1].s = frac_r.s;
            jobs[1].prev = 0u;
            jobs[1].q = ivec2(pixel);
            jobs[1].source = frac_r.pad;
            n_jobs = 2u;
        }
    }

    // Moving shapes: re-evaluate each previous sample's target in its own domain (job n_prev + j - 1
    // for job j).
    uint n_prev = n_jobs;
    if (pc.shapesMoved != 0u) {
        for (uint j = 1u; j < n_prev; ++j) {
            ivec2 q = slot_q[jobs[j].source];
            jobs[n_jobs].s = reservoirs_prev[pixel_index(q)].s;
            jobs[n_jobs].prev = 1u;
            jobs[n_jobs].q = q;
            jobs[n_jobs].source = jobs[j].source;
            ++n_jobs;
        }
    }

    vec3 F[MAX_JOBS];
    for (uint j = 0u; j < n_jobs; ++j) {
        F[j] = vec3(0.0);
        if (j == 0u && (!canonical_partner || rc.W <= 0.0)) continue;
        ShiftJob job = jobs[j];
        PrimaryHit h = job.prev != 0u ? primary_prev[pixel_index(job.q)] : hc;
        PrimaryHit dst = restir_domain_primary(cfg, job.s, h, job.q,
                                               job.prev != 0u ? scene_info.camera_prev : scene_info.camera_open);
        F[j] = restir_shift(cfg, job.s, dst);
    }

    float t_cp = luminance(F[0]);
    float M_partner = canonical_partner ? slot_M[jobs[0].source] : 0.0;
    PathReservoir r = reservoir_empty();
    for (uint j = 1u; j < n_prev; ++j) {
        uint sl = jobs[j].source;
        PathReservoir rq = reservoirs_prev[pixel_index(slot_q[sl])];
        float t_prev = rq.target, W = rq.W;
        if (fractional && pc.areaVariant == AREA_FAST) {
            t_prev = frac_r.target;
            W = W_frac;
        }
        if (pc.shapesMoved != 0u) t_prev = luminance(F[n_prev + j - 1u]);
        float t_qc = luminance(F[j]);
        float m_q;
        if (pc.mis == TEMPORAL_MIS_BALANCE) {
            m_q = mis_balance2(slot_M[sl], t_prev, Mc, t_qc);
        } else {
            m_q = slot_M[sl] / (slot_M[sl] + Mc);
        }
        reservoir_add(r, jobs[j].s, F[j], t_qc, m_q * t_qc * W, rng_next(rng));
    }
    float m_c;
    if (pc.mis == TEMPORAL_MIS_BALANCE) {
        m_c = mis_balance2(Mc, rc.target, M_partner, t_cp);
    } else {
        // 1/|Z(x)| with confidences: only techniques that can produce x count. With
        // countFailedShifts the previous frame is counted even when Y_c cannot shift there.
        bool counts = t_cp > 0.0 || (pc.countFailedShifts != 0u && canonical_partner);
        m_c = Mc / (Mc + (counts ? M_partner : 0.0));
    }
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));
    r.M = Mc + M_prev;
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
}
