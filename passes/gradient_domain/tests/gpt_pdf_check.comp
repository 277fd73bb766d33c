#version 460
// Test kernel: every candidate sub-path of one path per pixel (generation.glsl's callback, as
// G-PT uses it) shifted to its own pixel's primary hit must reproduce the generator's integrand
// F = C p_mixed and the generator's reconnection density p_rc (GenState) through the shift's
// restir_reconnection_pdf: the two codes that G-PT's MIS weights compare agree on the same
// path. Per pixel: candidates, wrong integrands, wrong densities, candidates with reconnection.
#define RESTIR_CANDIDATE_CALLBACK
#include "lib/restir/generation.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/primary.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D checkImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint shift;
    float roughnessThreshold;
} pc;

RestirSettings g_cfg;
PrimaryHit g_self;
vec4 g_counts;

void restir_candidate(inout PathReservoir r, inout Rng rng_sel, PathSample s, vec3 C,
                      float p_mixed, float p_rc, float inv_candidates, float rr_weight) {
    // Candidates of zero contribution (e.g. an environment hit with zero MIS weight) are not
    // sampled paths of the estimator: G-PT skips them.
    if (!any(greaterThan(C, vec3(0.0)))) return;
    ShiftDensity self;
    vec3 F = C * p_mixed;
    vec3 F_self = restir_shift_with_density(g_cfg, s, g_self, self);
    g_counts.x += 1.0;
    if (any(greaterThan(abs(F_self - F), 1e-3 * max(F, vec3(1e-8))))) g_counts.y += 1.0;
    if (!(abs(self.p_rc - p_rc) <= 1e-3 * p_rc)) g_counts.z += 1.0;
    if (path_rc_index(s) != 0u) g_counts.w += 1.0;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    g_cfg.max_bounces = 5u;
    g_cfg.shift = pc.shift;
    g_cfg.rough_threshold = pc.roughnessThreshold;
    g_cfg.dist_threshold = 0.1;
    g_cfg.frame_size = pc.frameSize;
    g_cfg.mis_heuristic = MIS_HEURISTIC_POWER;
    g_cfg.area = 0u;
    g_cfg.covered_max_chain = g_cfg.covered_depth = 0u;
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed);
    vec4 film_lens = vec4(rng_next2(rng), rng_next2(rng));
    g_self = restir_trace_primary(scene_info.camera_open, ivec2(pixel), film_lens, pc.frameSize);
    g_counts = vec4(0.0);
    PathReservoir unused = reservoir_empty();
    restir_generate(g_cfg, g_self, rng_init(pixel, pc.frameIndex, pc.seed ^ 0x9E3779B1u).state,
                    film_lens, 0.0, 1.0, 64u, unused, rng);
    imageStore(checkImage, ivec2(pixel), g_counts);
}
