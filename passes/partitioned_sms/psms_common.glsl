// What the PartitionedSMS kernels share: parameters (filled by name from the pass's
// declaration), the per-pixel estimator state carried across dispatches, the frame's counters
// and the seed-space sampling of Hong et al. 2025 Eq. 7-9. Layouts mirrored by
// PartitionedSMSPass.cpp.
#ifndef LOOM_PASSES_PSMS_COMMON_GLSL
#define LOOM_PASSES_PSMS_COMMON_GLSL

#define MANIFOLD_TRUST_REGION 1
#include "lib/manifold/pairs.glsl"
#include "lib/manifold/reservoir.glsl"
#include "lib/manifold/partition.glsl"
#include "lib/manifold/prior.glsl"
#include "lib/manifold/seed_space.glsl"
#include "lib/manifold/sms.glsl"
#include "lib/rng.glsl"
#include "lib/work_list.glsl"

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint tiles;                // N: the seed space is cut into N x N tiles (1: plain SMS)
    uint prior;                // read ManifoldPrior's tile sets (0: partitioning alone)
    float alpha;               // mixture weight of the prior, for the pair and the seed
    uint constraint;           // MANIFOLD_CONSTRAINT_*
    uint stepControl;          // MANIFOLD_STEP_*
    uint maxIterations;
    float solverThreshold;
    float uniquenessThreshold;
    uint maxTrials;
    uint trialCap;             // TRIAL_CAP_*
    uint maxChain;
    float geometricTermClamp;  // 0 = off
    uint maxBounces;
    uint rrDepth;
    uint misHeuristic;
    uint excludeCovered;
    uint stepBudget;
    float minSegment;
    uint dispatchIndex;
} pc;

const uint PSMS_NONE = 0u;       // no estimate at this pixel
const uint PSMS_FIRST = 1u;      // the sample's own walk
const uint PSMS_BERNOULLI = 2u;  // trials in C(u*) until that solution is found again
const uint PSMS_DONE = 3u;

struct PsmsPixel {
    uvec4 hit;     // x0: x prim, yz barycentrics (bits), w status
    vec4 wo;       // xyz direction from x0 towards the camera, w P(C(u*)) (Eq. 8)
    uvec4 rng;     // the estimator's random stream
    vec4 light_y;  // xyz light point, w its pdf (pair choice included)
    vec4 light_n;  // xyz area light normal (0: point or directional), w light index (bits)
    vec4 target;   // xyz the solution's first direction, w trials so far (K)
    vec4 value;    // rgb the solution's contribution (DONE: times K / P(C))
    uvec4 counts;  // x Newton iterations, y walks, z solution found, w trial cap reached
    uvec4 pair;    // x pair, y its slot in the block's list (~0u: none), z #I, w the tile of
                   // u*, x | y << 8, | #(I n C(u*)) << 16
    vec4 x1;       // xyz the solution's first vertex, w the estimate's weight K / P(C) (DONE)
    uvec4 shapes;  // the solution's shape sequence (MANIFOLD_NO_SHAPE after the last)
    vec4 camera;   // xyz the camera ray's origin (x0 is seen from there), w unused
};
layout(std430) buffer PsmsPixels { PsmsPixel psms_pixels[]; };

// Frame totals (Hong et al. 2025 Table 1 columns are ratios of these).
layout(std430) buffer PsmsCounters {
    uint psms_samples;     // estimates started (receivers with a light point)
    uint psms_solved;      // of which the first walk found a solution
    uint psms_iterations;  // Newton steps over all walks, failed ones included
    uint psms_walks;       // walks, the first one included
    uint psms_bernoulli;   // Bernoulli trials of the estimates that found one
    uint psms_capped;      // estimates that reached maxTrials or ran out of dispatches
    uint psms_max_bvh_iterations;
    uint psms_rays;
};

uint psms_pixel_index(uvec2 p) { return p.y * pc.frameSize.x + p.x; }

// Rough casters: the estimate's offset normals' stream, two words of its random stream (whose
// xyz the trials leave unchanged): the first walk and every Bernoulli trial take the same
// offsets, and the reservoir keeps the words for the manifold shift.
uvec2 psms_offset_seed(PsmsPixel st) {
    return uvec2(st.rng.x | (st.rng.y << 16u), st.rng.z ^ 0x0FF5E7A1u);
}

ManifoldSettings psms_settings() {
    ManifoldSettings ms;
    ms.constraint = pc.constraint;
    ms.step_control = pc.stepControl;
    ms.max_iterations = pc.maxIterations;
    ms.solver_threshold = pc.solverThreshold;
    ms.min_segment = pc.minSegment;
    ms.max_chain = min(pc.maxChain, uint(MANIFOLD_MAX_VERTICES));
    return ms;
}

// ManifoldPrior's slot of the sample's pair is the tile set of lib/manifold/partition.glsl.
bool partition_tile_in_set(uint set, uvec2 tile, uint tiles) {
    return prior_tile_set(set, tile, tiles);
}

// The sample's partition: its pair's tile set I in the pixel's block (#I = 0: none).
ManifoldPartition psms_partition(PsmsPixel st, uvec2 pixel) {
    ManifoldPartition p;
    p.tiles = pc.tiles;
    p.set = st.pair.y == ~0u ? 0u : prior_slot_base(prior_block(pixel, pc.frameSize), st.pair.y);
    p.set_size = st.pair.z;
    p.alpha = pc.alpha;
    return p;
}

#endif
