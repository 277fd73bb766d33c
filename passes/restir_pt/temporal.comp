#version 460
// ReSTIR PT temporal reuse (Lin et al. 2022, Sec. 7): the previous frame's final reservoir at
// the motion-vector reprojected pixel is shifted into this pixel and combined with the current
// one by the 2-technique generalized balance heuristic (Talbot) with confidences; the history's
// confidence is clamped to confidenceCap times the current one.
#include "lib/color.glsl"
#include "lib/mis.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/primary.glsl"
#include "lib/restir/primary_shift.glsl"
#include "lib/restir/reservoir.glsl"
#include "lib/restir/temporal.glsl"

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

// Members are filled by name from ReSTIRPTTemporal's declared parameters (KernelParams.h);
// enum parameters arrive as indices named by generated defines: MIS_BALANCE (generalized
// balance heuristic) / MIS_UNIFORM (confidence weights over techniques that can shift),
// AREA_REPROJECTION_*, MOVING_SUFFIX_*, DOF_SHIFT_*.
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint historyReset;  // the previous-frame inputs hold no frame yet
    uint mis;
    uint countFailedShifts;  // ablation: reproduces the "failed shift in the denominator" bias
    uint areaReprojection;
    float confidenceCap;
    float normalThreshold;
    float depthThreshold;
    uint dofShift;
    uint movingSuffix;
} pc;

// Area ReSTIR temporal reprojection (Zhang et al. 2024, Sec. 5). Samples carry film positions, so
// the previous frame's samples are translated by this pixel's fractional motion vector t (a
// bijection with Jacobian 1). The current pixel's footprint in the previous film, [p, p+1)^2 + t,
// overlaps up to four previous pixels whose parts are disjoint: each previous pixel is a
// technique covering only its part.
// AREA_REPROJECTION_FAST: RIS over the 2x2 block by previous targets, shift the winner;
// AREA_REPROJECTION_ROBUST: shift all four first, resample by current targets;
// AREA_REPROJECTION_COPY: one previous pixel, subpixel offset copied (no fraction).

bool prev_pixel_usable(ivec2 q, PrimaryHit hc) {
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.frameSize)))) return false;
    return restir_similar(hc, primary_prev[uint(q.y) * pc.frameSize.x + uint(q.x)], true,
                          pc.normalThreshold, pc.depthThreshold);
}

uint pixel_index(ivec2 q) { return uint(q.y) * pc.frameSize.x + uint(q.x); }

// Shift jobs, all run through one restir_shift call site (lavapipe compiles every inlined copy
// of the shift and its BVH traversals separately: code size is speed). A job takes sample s from
// its own domain (pixel src_q of this or the previous frame) to film offset dst_off of pixel
// dst_q, by lens-vertex copy (film offset and lens sample replayed) or, for Area ReSTIR under a
// thin lens, by primary-hit reconnection (x1 kept, lens point solved; Zhang et al. 2024 Sec. 6).
// Jobs: the canonical sample to its previous-frame partner (one per shift) and the previous
// samples to this pixel (one per shift). A job is evaluated in its destination frame's
// geometry (scene_select_frame), so with moving shapes the canonical sample's target in the
// previous domain sees the previous frame's shapes, as the stored previous targets did.
//
bool shift_crosses_moved_suffix(PathSample s) {
    return restir_crosses_moved_suffix(s, pc.movingSuffix == MOVING_SUFFIX_REJECT);
}
const uint MAX_PREV_SLOTS = 4u;
const uint MAX_JOBS = 2u + 2u * MAX_PREV_SLOTS;
struct ShiftJob {
    PathSample s;     // in its own domain
    ivec2 src_q;
    uint src_prev;    // 1: the source domain is a previous-frame pixel
    ivec2 dst_q;
    uint dst_prev;
    vec2 dst_off;     // film offset in the destination pixel
    uint shift;       // SHIFT_COPY or SHIFT_PRIMARY_RECONNECT
    uint source;      // previous pixel slot of the sample
};

ShiftJob shift_job(PathSample s, ivec2 src_q, uint src_prev, ivec2 dst_q, uint dst_prev,
                   vec2 dst_off, uint shift, uint source) {
    ShiftJob j;
    j.s = s;
    j.src_q = src_q;
    j.src_prev = src_prev;
    j.dst_q = dst_q;
    j.dst_prev = dst_prev;
    j.dst_off = dst_off;
    j.shift = shift;
    j.source = source;
    return j;
}

// The camera the sample sees in a frame (with motion blur, at its shutter time: copied by every
// temporal shift, so a gathered previous sample keeps its shutter fraction).
CameraPose pose_of(RestirSettings cfg, PathSample s, uint prev) {
    return restir_sample_pose(cfg, s, prev != 0u);
}
PrimaryHit primary_of(uint prev, ivec2 q) {
    return prev != 0u ? primary_prev[pixel_index(q)] : primary_in[pixel_index(q)];
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    RestirSettings cfg = settings_in;
    if (idx == 0u) settings_out = cfg;
    PathReservoir rc = reservoirs_in[idx];
    PrimaryHit hc = primary_in[idx];
    bool same_rules = restir_same_rules(settings_prev, cfg);
    if (pc.historyReset != 0u || !same_rules || !primary_valid(hc)) {
        reservoirs_out[idx] = rc;
        return;
    }
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x7E3A1F55u);
    float Mc = rc.M, cap = pc.confidenceCap * rc.M;
    bool fractional = cfg.area != 0u && pc.areaReprojection != AREA_REPROJECTION_COPY;
    vec2 t = imageLoad(motionImage, ivec2(pixel)).xy;
    // Shift mappings: each is a technique per previous pixel with 1 / n_shifts of its confidence,
    // combined with the canonical technique by pairwise MIS (with one shift: the 2-technique
    // generalized balance heuristic). Primary-hit reconnection needs the balance heuristic.
    uint shifts = SHIFT_COPY;
    if (cfg.area != 0u && pc.mis == MIS_BALANCE && camera_aperture(scene_info.camera_open) > 0.0 &&
        camera_aperture(scene_info.camera_prev) > 0.0)
        shifts = dof_shift_mask(pc.dofShift);
    float n_shifts = float(bitCount(shifts));

    // Previous-frame techniques: one pixel (ReSTIR PT, Area copy) or the 2x2 footprint block.
    ivec2 slot_q[MAX_PREV_SLOTS];
    float slot_M[MAX_PREV_SLOTS];
    uint slots = 0u;
    // Samples shifted here: (own sample, film offset here, slot).
    PathSample in_s[MAX_PREV_SLOTS];
    vec2 in_off[MAX_PREV_SLOTS];
    uint in_slot[MAX_PREV_SLOTS];
    uint n_in = 0u;
    bool canonical_partner = false;
    ivec2 partner_q = ivec2(0);
    uint partner_slot = 0u;
    vec2 partner_off = vec2(0.0);  // the canonical sample's film offset in its partner pixel
    float M_prev = 0.0;
    PathReservoir frac_r = reservoir_empty();  // AREA_REPROJECTION_FAST: the fractional reservoir
    float W_frac = 0.0;
    if (!fractional) {
        ivec2 q = ivec2(floor(vec2(pixel) + 0.5 + t));
        if (prev_pixel_usable(q, hc)) {
            PathReservoir rp = reservoirs_prev[pixel_index(q)];
            slot_q[0] = q;
            slot_M[0] = min(rp.M, cap);
            slots = 1u;
            M_prev = slot_M[0];
            canonical_partner = true;
            partner_q = q;
            partner_off = rc.s.film_lens.xy;
            if (rp.W > 0.0) {
                in_s[0] = rp.s;
                in_off[0] = rp.s.film_lens.xy;
                in_slot[0] = 0u;
                n_in = 1u;
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
                partner_q = q;
                partner_slot = sl;
                partner_off = Xc - vec2(qc);
            }
            // Its sample lands in this pixel only from its part of the footprint.
            vec2 X = vec2(q) + rq.s.film_lens.xy - t;
            if (rq.W <= 0.0 || any(lessThan(X, vec2(pixel))) || any(greaterThanEqual(X, vec2(pixel) + 1.0)))
                continue;
            if (pc.areaReprojection == AREA_REPROJECTION_FAST) {
                // Resample by the previous targets (no shift yet); parts are disjoint: weight 1.
                PathSample sq = rq.s;
                sq.film_lens.xy = X - vec2(pixel);
                if (reservoir_add(frac_r, sq, vec3(0.0), rq.target, rq.target * rq.W, rng_next(rng)))
                    frac_r.pad = sl;
                continue;
            }
            in_s[n_in] = rq.s;
            in_off[n_in] = X - vec2(pixel);
            in_slot[n_in] = sl;
            ++n_in;
        }
        if (pc.areaReprojection == AREA_REPROJECTION_FAST && frac_r.w_sum > 0.0) {
            W_frac = frac_r.w_sum / frac_r.target;
            in_s[0] = reservoirs_prev[pixel_index(slot_q[frac_r.pad])].s;
            in_off[0] = frac_r.s.film_lens.xy;
            in_slot[0] = frac_r.pad;
            n_in = 1u;
        }
    }

    // Jobs: [0, n_c) canonical -> partner, one per shift; [n_c, n_c + n_in * n_shifts) previous
    // samples -> here.
    ShiftJob jobs[MAX_JOBS];
    uint n_jobs = 0u;
    for (uint sh = SHIFT_COPY; sh <= SHIFT_PRIMARY_RECONNECT; sh <<= 1)
        if ((shifts & sh) != 0u && canonical_partner && rc.W > 0.0)
            jobs[n_jobs++] = shift_job(rc.s, ivec2(pixel), 0u, partner_q, 1u, partner_off, sh, partner_slot);
    uint n_c = n_jobs;
    for (uint i = 0u; i < n_in; ++i)
        for (uint sh = SHIFT_COPY; sh <= SHIFT_PRIMARY_RECONNECT; sh <<= 1)
            if ((shifts & sh) != 0u)
                jobs[n_jobs++] = shift_job(in_s[i], slot_q[in_slot[i]], 1u, ivec2(pixel), 0u,
                                           in_off[i], sh, in_slot[i]);
    uint n_here = n_jobs;

    vec3 F[MAX_JOBS];
    float J[MAX_JOBS];
    PathSample s_out[MAX_JOBS];
    for (uint j = 0u; j < n_jobs; ++j) {
        ShiftJob job = jobs[j];
        PathSample s_dst = job.s;
        s_dst.film_lens.xy = job.dst_off;
        CameraPose dst_pose = pose_of(cfg, job.s, job.dst_prev);
        PrimaryHit dst;
        J[j] = 1.0;
        bool ok = !shift_crosses_moved_suffix(job.s);
        if (job.shift == SHIFT_COPY) {
            // Copy: replay the film/lens sample in the destination (Jacobian 1).
            scene_select_frame(job.dst_prev != 0u);
            dst = restir_domain_primary(cfg, s_dst, primary_of(job.dst_prev, job.dst_q), job.dst_q,
                                        dst_pose);
        } else {
            // Reconnection: the source domain's primary hit, kept, with the lens point solved for
            // in the destination.
            CameraPose src_pose = pose_of(cfg, job.s, job.src_prev);
            scene_select_frame(job.src_prev != 0u);
            PrimaryHit src = restir_domain_primary(cfg, job.s, primary_of(job.src_prev, job.src_q),
                                                   job.src_q, src_pose);
            PathSample s_rec;
            ok = ok && restir_primary_reconnect(job.s, src, vec2(job.src_q) + job.s.film_lens.xy, src_pose,
                                          job.src_prev != 0u, vec2(job.dst_q) + job.dst_off,
                                          dst_pose, job.dst_prev != 0u, pc.frameSize, s_rec, dst,
                                          J[j]);
            s_dst.film_lens.zw = s_rec.film_lens.zw;
        }
        F[j] = ok ? restir_shift(cfg, s_dst, dst) : vec3(0.0);
        s_out[j] = s_dst;
    }
    scene_select_frame(false);

    // Pairwise MIS over the shifts (Lin et al. 2022 Sec. 7.2, non-defensive; with one shift the
    // 2-technique balance heuristic): technique (q, shift) with confidence M_q / n_shifts,
    //   previous sample x = T(x_q):  m = b(x) / n_shifts,
    //   canonical y_c:               m_c = sum over shifts of (1 - b(y_c)) / n_shifts,
    // b = balance(M_q / n_shifts * p_hat_q pulled back here, M_c * p_hat_c), the pull-back of a
    // target carrying the shift's Jacobian (Lin et al. Eq. 9).
    PathReservoir r = reservoir_empty();
    for (uint j = n_c; j < n_here; ++j) {
        uint sl = jobs[j].source;
        PathReservoir rq = reservoirs_prev[pixel_index(slot_q[sl])];
        float t_prev = rq.target, W = rq.W;
        if (fractional && pc.areaReprojection == AREA_REPROJECTION_FAST) {
            t_prev = frac_r.target;
            W = W_frac;
        }
        float t_qc = luminance(F[j]);
        float m_q;
        if (pc.mis == MIS_BALANCE) {
            float t_own = J[j] > 0.0 ? t_prev / J[j] : 0.0;
            m_q = mis_balance2(slot_M[sl] / n_shifts, t_own, Mc, t_qc) / n_shifts;
        } else {
            m_q = slot_M[sl] / (slot_M[sl] + Mc);
        }
        reservoir_add(r, s_out[j], F[j], t_qc, m_q * t_qc * W * J[j], rng_next(rng));
    }
    float M_partner = canonical_partner ? slot_M[partner_slot] : 0.0;
    float m_c;
    if (pc.mis == MIS_BALANCE) {
        m_c = 0.0;
        uint k = 0u;
        for (uint sh = SHIFT_COPY; sh <= SHIFT_PRIMARY_RECONNECT; sh <<= 1) {
            if ((shifts & sh) == 0u) continue;
            float t_cp = k < n_c ? luminance(F[k]) * J[k] : 0.0;
            m_c += mis_balance2(Mc, rc.target, M_partner / n_shifts, t_cp) / n_shifts;
            ++k;
        }
    } else {
        // 1/|Z(x)| with confidences: only techniques that can produce x count. With
        // countFailedShifts the previous frame is counted even when Y_c cannot shift there.
        float t_cp = n_c > 0u ? luminance(F[0]) : 0.0;
        bool counts = t_cp > 0.0 || (pc.countFailedShifts != 0u && canonical_partner);
        m_c = Mc / (Mc + (counts ? M_partner : 0.0));
    }
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));
    r.M = Mc + M_prev;
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
}
