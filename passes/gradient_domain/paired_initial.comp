#version 460
// Initial paired-pixel reservoirs of gradient-domain ReSTIR PT (Wang et al. 2025, Sec. 4.2):
// the pair (p, p + e) resamples the two pixels' initial path candidates (the same ones Area
// ReSTIR's primal chain starts from), p's as (s, 0) and p + e's as (s, 1). Each candidate
// (s, W) comes from its own half of the paired-pixel domain, so its resampling weight is
// target * W with MIS weight 1. The inner shift evaluates each at its partner pixel. Also writes
// the pixels' G-buffer features for the reuse passes' tests.
#include "passes/gradient_domain/paired_pixel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(std430) writeonly buffer PairsOut {
    PairSettings pair_settings_out;
    PairSlots pairs_out[];
};
layout(std430) writeonly buffer FeaturesOut { PixelFeatures features_out[]; };

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint positivization;
    uint measure;  // PAIR_MEASURE_*, from the generated MEASURE_* indices (same order)
} pc;

uint pixel_index(ivec2 q) { return uint(q.y) * pc.frameSize.x + uint(q.x); }

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    uint idx = pixel_index(p);
    PairSettings ps;
    ps.restir = settings_in;
    ps.positivization = pc.positivization;
    ps.measure = pc.measure;
    if (idx == 0u) pair_settings_out = ps;
    features_out[idx] = pixel_features(primary_in[idx], false);
    bool solid_angle = ps.measure == PAIR_MEASURE_SOLID_ANGLE;

    // Evaluations: 2d + b = candidate b of direction d's pair at its partner; in the solid-angle
    // measure also 4, 5, 6 = the candidates of p, p + e_x, p + e_y at their own pixel (for their
    // measure factor there).
    PathReservoir cand[3];
    cand[0] = reservoirs_in[idx];
    for (uint d = 0u; d < 2u; ++d)
        cand[1u + d] = pair_inside(p, d, pc.frameSize) ? reservoirs_in[pixel_index(pair_pixel(p, d, 1u))]
                                                      : reservoir_empty();
    vec3 F_partner[4];
    float solid_own[3] = float[3](1.0, 1.0, 1.0);
    for (uint i = 0u; i < (solid_angle ? 7u : 4u); ++i) {
        uint d = i < 4u ? i >> 1 : 0u, b = i & 1u;
        uint c = i < 4u ? (b == 0u ? 0u : 1u + d) : i - 4u;  // the candidate evaluated
        if (i < 4u) F_partner[i] = vec3(0.0);
        if (!(cand[c].W > 0.0) || (i < 4u && !pair_inside(p, d, pc.frameSize))) continue;
        ivec2 dst = i < 4u ? pair_pixel(p, d, 1u - b) : (c == 0u ? p : pair_pixel(p, c - 1u, 1u));
        float solid;
        vec3 F = pair_eval(ps, pair_eval_at(cand[c].s, primary_in[pixel_index(dst)], dst, false), solid);
        if (i < 4u) F_partner[i] = F;
        else solid_own[c] = solid;
    }

    Rng rng = rng_init(uvec2(p), pc.frameIndex, pc.seed ^ 0x2C1B3C6Du);
    PairSlots out_slots;
    for (uint slot = 0u; slot < 4u; ++slot) {
        uint d = slot >> 1, sign = slot & 1u;
        PairStream st = pair_stream_begin();
        bool in_use = sign < pair_signs(ps) && pair_inside(p, d, pc.frameSize);
        if (in_use) {
            for (uint b = 0u; b < 2u; ++b) {
                uint c = b == 0u ? 0u : 1u + d;
                if (!(cand[c].W > 0.0)) continue;
                float solid = solid_own[c];
                vec3 g = pair_integrand(cand[c].F, F_partner[2u * d + b], b, solid);
                float t = pair_target(g, sign, ps.positivization != 0u);
                // The candidate's contribution weight in the pair measure: W / solid.
                pair_stream_add(st, cand[c].s, g, t, t * cand[c].W / solid, rng_next(rng), b, solid);
            }
        }
        out_slots.slot[slot] = pair_stream_end(st, in_use ? 1.0 : 0.0);
    }
    pairs_out[idx] = out_slots;
}
