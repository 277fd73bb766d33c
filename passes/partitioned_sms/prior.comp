#version 460
// ManifoldPrior (Hong et al. 2025 Sec. 4.2): presample threads per B x B pixel block, each at
// a random pixel of its block, with a random light-caster pair, a random point on its emitter
// and a uniform seed, run one unrestricted walk; the fine tile of every solution is OR-ed into
// the block's set I for that pair. Workgroup (x, y): presamples x .. x + 63 of block y.
#define MANIFOLD_TRUST_REGION 1
#include "lib/bvh.glsl"
#include "lib/camera.glsl"
#include "lib/manifold/pairs.glsl"
#include "lib/manifold/prior.glsl"
#include "lib/manifold/sms.glsl"
#include "lib/rng.glsl"

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint constraint;
    uint maxIterations;
    float solverThreshold;
    uint maxChain;
    float minSegment;
} pc;

layout(std430) buffer PriorCounters {
    uint prior_walks;      // walks started (presamples at a receiver with a light point)
    uint prior_solutions;  // walks that found a visible solution
    uint prior_overflow;   // solutions dropped: the block's list was full
    uint prior_iterations;
    uint prior_max_bvh_iterations;
};

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    uint block = gl_WorkGroupID.y;
    uint blocks_x = (pc.frameSize.x + PRIOR_BLOCK - 1u) / PRIOR_BLOCK;
    uvec2 origin = uvec2(block % blocks_x, block / blocks_x) * PRIOR_BLOCK;
    uint thread = gl_WorkGroupID.x * 64u + gl_LocalInvocationIndex;
    Rng rng = rng_init(uvec2(block, thread), pc.frameIndex, pc.seed ^ 0x9E1F0A5Bu);
    uvec2 extent = min(uvec2(PRIOR_BLOCK), pc.frameSize - origin);
    uvec2 pixel = origin + min(uvec2(rng_next2(rng) * vec2(extent)), extent - 1u);
    vec2 uv = (vec2(pixel) + rng_next2(rng)) / vec2(pc.frameSize);
    CameraFrame cam = camera_frame(scene_info.camera_open, scene_info.camera_close, 0.0);
    vec3 o, d;
    camera_ray(cam, uv, vec2(0.5), o, d);

    ManifoldSettings ms;
    ms.constraint = pc.constraint;
    ms.step_control = MANIFOLD_STEP_REPROJECTION;
    ms.max_iterations = pc.maxIterations;
    ms.solver_threshold = pc.solverThreshold;
    ms.min_segment = pc.minSegment;
    ms.max_chain = min(pc.maxChain, uint(MANIFOLD_MAX_VERTICES));

    // One trace call site: the camera ray first (camera = true), then the walk's rays.
    bool camera = true;
    uint pair = 0u;
    ManifoldTrial tr;
    tr.phase = TRIAL_FAILED;
    tr.iterations = 0u;
    vec3 ray_o = o, ray_d = d;
    float ray_tmin = 0.0, ray_tmax = 1e30;
    for (;;) {
        Hit hit;
        bool found = trace_closest(ray_o, ray_d, ray_tmin, ray_tmax, BVH_MASK_ALL, hit);
        if (camera) {
            camera = false;
            if (!found) break;
            ShadingPoint sh = shading_point(hit);
            if (!manifold_receiver(sh.shape_flags, sh.mat)) break;
            uint pairs = manifold_pair_count();
            pair = min(uint(rng_next(rng) * float(pairs)), pairs - 1u);
            ManifoldLight ml = manifold_sample_pair_light(pair, vec3(rng_next2(rng), rng_next(rng)), 1.0);
            if (!ml.valid) break;
            ManifoldReceiver rc = manifold_receiver(sh, -d, ml);
            uint caster = manifold_pair_caster(pair);
            ManifoldSeedSpace space = manifold_seed_space(rc.x0, rc.ng0, manifold_caster_bound(caster));
            vec3 w = manifold_seed_direction(space, rng_next2(rng));
            tr = manifold_trial_start(rc.x0, rc.ng0, ml.y, ml.n, rc.es, rc.et, ml.directional,
                                      false, rc.x0 + w);
            tr.space = space;
            tr.tiles = 1u;  // unrestricted
            tr.region = uvec2(0u);
            tr.first_shape = manifold_caster_shape(caster);
#ifdef MANIFOLD_ROUGH_CASTERS
            // Offset normals of the presample's own (the prior only proposes seeds).
            tr.offset_stream = manifold_offset_stream(uvec2(rng_next_uint(rng), rng_next_uint(rng)));
#endif
            atomicAdd(prior_walks, 1u);
        } else {
            manifold_trial_advance(tr, found, hit, ms);
        }
        if (!manifold_trial_running(tr)) break;
        ray_o = tr.ray_o;
        ray_d = tr.ray_d;
        ray_tmin = tr.ray_tmin;
        ray_tmax = tr.ray_tmax;
    }
    if (tr.phase == TRIAL_CONVERGED) {
        vec2 u;
        if (manifold_seed_coords(tr.space, manifold_trial_direction(tr), u)) {
            atomicAdd(prior_solutions, 1u);
            if (!prior_insert(block, pair, manifold_seed_tile(u, PRIOR_FINE_TILES)))
                atomicAdd(prior_overflow, 1u);
        }
    }
    atomicAdd(prior_iterations, tr.iterations);
    atomicMax(prior_max_bvh_iterations, bvh_iterations);
}
