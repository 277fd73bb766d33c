#version 460
// Gradient-domain path tracing (Kettunen et al. 2015, "Gradient-Domain Path Tracing"): one base
// path per pixel, shifted to the four neighbouring pixels by ReSTIR PT's hybrid shift (random
// replay up to the reconnection vertex, then reconnection: hybrid_shift.glsl, the shift Lin et
// al. 2022 build on Kettunen's). Every sub-path the path tracer would score (each NEE sample and
// each emitter hit, generation.glsl's candidates) is shifted on its own, so each gets its own
// balance-heuristic weight between the two ways of sampling the pair: here and shifted to the
// neighbour, or at the neighbour and shifted back (Kettunen Eq. 9, 10). In the shifts' mixed
// measure the Jacobian is 1 and the weight is w = p / (p + p'), with p' the neighbour's density
// of the offset path; only the factors around the reconnection vertex differ (p_rc).
//
// Per pixel and direction d (+x, -x, +y, -y) this writes the weighted difference w (f' - f) / p
// (an estimate of I(neighbour) - I(here): one side of the two-sided gradient; gpt_resolve.comp
// adds the neighbour's opposite side), the primal w f / p and the neighbour's primal share
// w f' / p. The emission seen at the primary hit is excluded from all of them and written apart
// (Kettunen Sec. 5: added back after the reconstruction).
#define RESTIR_CANDIDATE_CALLBACK
#include "lib/camera.glsl"
#include "lib/restir/generation.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/primary.glsl"
#include "passes/gradient_domain/gradient_pixels.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// One pixel's sums over this frame's samples (primal: sum_d w_d f / p / 4; neighbour shares
// w_d f' / p / 4; gradients w_d (f' - f) / p); gpt_resolve.comp gathers them.
layout(std430) buffer GradientPixels { GradientPixel gradient_pixels[]; };
layout(std430) buffer RayCounter {
    uint ray_count;
    uint max_bvh_iterations;
};

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint sampleIndex;  // this dispatch's sample of the frame (0 overwrites the sums)
    uint maxBounces;
    uint shift;
    float roughnessThreshold;
    float distanceThreshold;
    uint misHeuristic;
    uint motionBlur;
    uint ablation;  // ABLATION_*: biased variants for the tests
} pc;

// The invocation's state for restir_candidate (generation.glsl's callback).
RestirSettings g_cfg;
PrimaryHit g_neighbour[4];
bool g_inside[4];
vec3 g_primal, g_share[4], g_gradient[4];

void restir_candidate(inout PathReservoir r, inout Rng rng_sel, PathSample s, vec3 C,
                      float p_mixed, float p_rc, float inv_candidates, float rr_weight) {
    // A sub-path of zero contribution is one the path tracer does not score: its pair is the
    // neighbour's to weigh alone (its shift back gives 0 here, so it takes weight 1).
    if (!any(greaterThan(C, vec3(0.0)))) return;
    for (uint d = 0u; d < 4u; ++d) {
        if (!g_inside[d]) {
            // No neighbour, no second technique: weight 1.
            g_primal += C;
            continue;
        }
        ShiftDensity offset;
        vec3 F_offset = restir_shift_with_density(g_cfg, s, g_neighbour[d], offset);
        // p' / p. A failed shift (or an offset path of zero contribution, which the neighbour's
        // own sampler never scores either) leaves the base path alone: w = 1.
        float ratio = any(greaterThan(F_offset, vec3(0.0))) ? offset.p_rc / p_rc : 0.0;
        if (!(ratio < 1e30)) continue;  // the neighbour's technique takes it all: w = 0
        float w = pc.ablation == ABLATION_HALF_WEIGHTS ? 0.5 : 1.0 / (1.0 + ratio);
        vec3 share = F_offset * (w / p_mixed);
        g_primal += w * C;
        g_share[d] += share;
        g_gradient[d] += (pc.ablation == ABLATION_FLIP_GRADIENT_SIGN ? -1.0 : 1.0) * (share - w * C);
    }
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    g_cfg.max_bounces = pc.maxBounces;
    g_cfg.shift = pc.shift;
    g_cfg.rough_threshold = pc.roughnessThreshold;
    g_cfg.dist_threshold = pc.distanceThreshold;
    g_cfg.frame_size = pc.frameSize;
    g_cfg.mis_heuristic = pc.misHeuristic;
    g_cfg.area = 0u;
    g_cfg.covered_max_chain = g_cfg.covered_depth = 0u;

    // The base path's film, lens and shutter samples; the offset paths replay them at their
    // pixel (primary sample space: Jacobian 1).
    uint stream = pc.seed ^ (0x632BE5ABu * (pc.sampleIndex + 1u));
    Rng rng = rng_init(pixel, pc.frameIndex, stream);
    vec4 film_lens = vec4(rng_next2(rng), rng_next2(rng));
    float time = pc.motionBlur != 0u ? rng_next(rng) : 0.0;
    CameraPose pose = camera_pose_at(scene_info.camera_open, scene_info.camera_close, time);
    PrimaryHit ph = restir_trace_primary(pose, ivec2(pixel), film_lens, pc.frameSize);
    uint rays = 1u;
    for (uint d = 0u; d < 4u; ++d) {
        ivec2 q = ivec2(pixel) + kGradientOffsets[d];
        g_inside[d] = gradient_inside(q, pc.frameSize);
        if (g_inside[d]) {
            g_neighbour[d] = restir_trace_primary(pose, q, film_lens, pc.frameSize);
            ++rays;
        }
        g_share[d] = vec3(0.0);
        g_gradient[d] = vec3(0.0);
    }
    g_primal = vec3(0.0);

    // No Russian roulette (rrDepth past the last vertex): the survival probability would be a
    // factor of the base path's density that the neighbour's sampler does not share.
    PathReservoir unused = reservoir_empty();
    uvec4 seed = rng_init(pixel, pc.frameIndex, stream ^ 0x9E3779B1u).state;
    rays += restir_generate(g_cfg, ph, seed, film_lens, time, 1.0, 64u, unused, rng);

    GradientPixel o;
    o.primal = vec4(0.25 * g_primal, 0.0);
    for (uint d = 0u; d < 4u; ++d) {
        o.neighbour[d] = vec4(0.25 * g_share[d], 0.0);
        o.gradient[d] = vec4(g_gradient[d], 0.0);
    }
    o.direct = vec4(restir_primary_emission(ph), 0.0);
    if (pc.sampleIndex != 0u) {
        GradientPixel a = gradient_pixels[idx];
        o.primal += a.primal;
        for (uint d = 0u; d < 4u; ++d) {
            o.neighbour[d] += a.neighbour[d];
            o.gradient[d] += a.gradient[d];
        }
        o.direct += a.direct;
    }
    gradient_pixels[idx] = o;
    atomicAdd(ray_count, rays);
    atomicMax(max_bvh_iterations, bvh_iterations);
}
