#version 460
// ReSTIR PT spatial reuse (Lin et al. 2022, Sec. 7): `neighbours` random pixels within `radius`,
// each neighbour's path shifted here (Area ReSTIR with depth of field: by lens-vertex copy and by
// primary-hit reconnection, Zhang et al. 2024 Sec. 6, each a technique of the MIS), combined
// with the canonical reservoir by defensive pairwise MIS (restir/reuse_mis.glsl): the canonical
// weight starts at 1, gains 1 - (neighbour's share of Y_c) per valid neighbour, and all weights
// are divided by (valid neighbours + 1).
#include "lib/color.glsl"
#include "lib/mis.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/primary.glsl"
#include "lib/restir/primary_shift.glsl"
#include "lib/restir/reservoir.glsl"
#include "lib/restir/reuse_mis.glsl"
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
    uint dofShift;  // DOF_SHIFT_*: Area ReSTIR under a thin lens
    uint mis;       // MIS_DEFENSIVE_PAIRWISE, MIS_PAIRWISE, MIS_BALANCE (generated defines)
} pc;


// A random neighbour in the disk of `radius`; false when it is this pixel, off screen, or
// geometrically dissimilar (then it is not a technique at all).
bool pick_neighbour(inout Rng rng, uvec2 pixel, PrimaryHit hc, out ivec2 q) {
    q = ivec2(vec2(pixel) + 0.5 + pc.radius * sample_disk_concentric(rng_next2(rng)));
    if (all(equal(q, ivec2(pixel))) || any(lessThan(q, ivec2(0))) ||
        any(greaterThanEqual(q, ivec2(pc.frameSize))))
        return false;
    return restir_similar(hc, primary_in[uint(q.y) * pc.frameSize.x + uint(q.x)], false,
                          pc.normalThreshold, pc.depthThreshold);
}

const uint MAX_NEIGHBOURS = 8u;
const uint MAX_TECHNIQUES = 2u * MAX_NEIGHBOURS;  // (neighbour, shift) pairs

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
    bool balance = pc.mis == MIS_BALANCE;
    // Techniques: each valid neighbour with each shift mapping (the replayed/copied film and lens
    // sample; with Area ReSTIR under a thin lens also primary-hit reconnection, each then with
    // half the neighbour's confidence). The balance heuristic uses the copy shift only.
    uint shifts = SHIFT_COPY;
    if (!balance && cfg.area != 0u && camera_aperture(scene_info.camera_open) > 0.0) shifts = dof_shift_mask(pc.dofShift);
    float n_shifts = float(bitCount(shifts));
    ivec2 tq[MAX_TECHNIQUES];
    uint tshift[MAX_TECHNIQUES];
    uint n = 0u;
    for (uint i = 0u; i < min(pc.neighbours, MAX_NEIGHBOURS); ++i) {
        ivec2 q;
        if (!pick_neighbour(rng, pixel, hc, q)) continue;
        for (uint t = SHIFT_COPY; t <= SHIFT_PRIMARY_RECONNECT; t <<= 1)
            if ((shifts & t) != 0u) {
                tq[n] = q;
                tshift[n] = t;
                ++n;
            }
    }

    // Every shift goes through the one call site below (lavapipe compiles each inlined copy of
    // the path shift, with its BVH traversals, separately: code size is speed).
    //   it <  n: technique it's sample shifted here          -> F_here, s_here, J_here
    //   it >= n: a sample shifted to technique b's domain    -> targets for the MIS weights
    //            (the canonical sample for pairwise; every sample for balance)
    vec3 F_here[MAX_TECHNIQUES];
    PathSample s_here[MAX_TECHNIQUES];
    float J_here[MAX_TECHNIQUES];
    float t_c_to[MAX_TECHNIQUES];   // canonical sample's target in technique b (times J)
    float den[MAX_TECHNIQUES + 1u]; // balance denominators (index n: canonical)
    for (uint i = 0u; i <= n; ++i) den[i] = 0.0;
    for (uint i = 0u; i < n; ++i) {  // neighbours with W <= 0 are skipped below
        F_here[i] = vec3(0.0);
        J_here[i] = 0.0;
        t_c_to[i] = 0.0;
    }
    uint sources = balance ? n + 1u : 1u;
    for (uint it = 0u; it < n + n * sources; ++it) {
        bool to_here = it < n;
        uint a = to_here ? it : (sources == 1u ? n : (it - n) % sources);  // source (n = canonical)
        uint b = to_here ? n : (it - n) / sources;                           // destination
        if (a == b) continue;
        uint tech = to_here ? a : b;  // the technique whose shift mapping is used
        PathReservoir ra = a == n ? rc : reservoirs_in[uint(tq[a].y) * pc.frameSize.x + uint(tq[a].x)];
        if (!(ra.W > 0.0) || (!to_here && a != n && !(luminance(F_here[a]) > 0.0))) continue;
        PathSample s_src = to_here || a == n ? ra.s : s_here[a];  // in its own / this domain
        ivec2 q_src = to_here ? tq[a] : ivec2(pixel);
        ivec2 q_dst = to_here ? ivec2(pixel) : tq[b];
        PrimaryHit h_src = to_here ? primary_in[uint(q_src.y) * pc.frameSize.x + uint(q_src.x)] : hc;
        PrimaryHit h_dst = to_here ? hc : primary_in[uint(q_dst.y) * pc.frameSize.x + uint(q_dst.x)];
        bool copy = tshift[tech] == SHIFT_COPY;
        // Copy: replay the film/lens sample in the destination. Reconnection: the source
        // domain's primary hit, kept, with the lens point solved for in the destination.
        // Motion blur: the shutter time is copied with the film and lens sample (Jacobian 1).
        CameraPose pose = restir_sample_pose(cfg, s_src, false);
        PrimaryHit base = restir_domain_primary(cfg, s_src, copy ? h_dst : h_src, copy ? q_dst : q_src, pose);
        PathSample s_dst = s_src;
        PrimaryHit dst = base;
        float J = 1.0;
        bool ok = copy || restir_primary_reconnect(s_src, base, vec2(q_src) + s_src.film_lens.xy, pose,
                                                    false, vec2(q_dst) + s_src.film_lens.xy, pose,
                                                    false, pc.frameSize, s_dst, dst, J);
        vec3 F = ok ? restir_shift(cfg, s_dst, dst) : vec3(0.0);
        if (to_here) {
            F_here[a] = F;
            s_here[a] = s_dst;
            J_here[a] = J;
        } else {
            float Mb = reservoirs_in[uint(q_dst.y) * pc.frameSize.x + uint(q_dst.x)].M / n_shifts;
            float t = luminance(F) * J;
            if (a == n) t_c_to[b] = t;
            den[a] += Mb * t;
        }
    }
    for (uint i = 0u; i < n; ++i)
        if (rc.W <= 0.0) t_c_to[i] = 0.0;

    PathReservoir r = reservoir_empty();
    float M = rc.M;
    float m_c = 1.0;
    for (uint i = 0u; i < n; ++i) {
        PathReservoir ri = reservoirs_in[uint(tq[i].y) * pc.frameSize.x + uint(tq[i].x)];
        float Mi = ri.M / n_shifts;
        M += Mi;
        float t = luminance(F_here[i]);
        float J = J_here[i];
        // Targets carry the shift's Jacobian (GRIS, Lin et al. Eq. 9): seen from here,
        // technique i's own target of this sample is p_hat_i(x_i) / J.
        float t_own = J > 0.0 ? ri.target / J : 0.0;
        float m_i;
        if (balance) {
            m_i = mis_balance(Mi * t_own, Mi * t_own + rc.M * t + den[i]);
        } else {
            m_i = pairwise_neighbour_weight(Mi, t_own, rc.M, t);
            m_c += pairwise_canonical_term(Mi, t_c_to[i], rc.M, rc.target);
        }
        if (ri.W > 0.0 && t > 0.0) reservoir_add(r, s_here[i], F_here[i], t, m_i * t * ri.W * J, rng_next(rng));
    }
    float norm = 1.0;
    if (balance) {
        m_c = mis_balance(rc.M * rc.target, rc.M * rc.target + den[n]);
    } else if (pc.mis == MIS_DEFENSIVE_PAIRWISE || n == 0u) {
        // Defensive: the canonical technique keeps a share 1 / (k + 1).
        norm = float(n + 1u);
    } else {
        // Non-defensive pairwise: divide by k, no extra canonical share.
        m_c -= 1.0;
        norm = float(n);
    }
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));
    r.w_sum /= norm;
    r.M = M;
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
}
