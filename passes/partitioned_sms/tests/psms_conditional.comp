#version 460
// Test kernel (test_psms.cpp): the partition's seed distributions at one receiver point with a
// tile set given as a mask (row y: bit x). Config in row 0 of the input: 0 (x0, mode),
// 1 (ng0, N), 2 (y, alpha), 3 (ny, maxIterations), 4 caster bounding sphere, 5 (target first
// direction, caster shape), 6 (es, #I), 7 (et, solver threshold), 8 + r: mask row r as
// (low 16 bits, high 16 bits).
//   mode 0, seed grid: invocation (i, j) walks from u = ((i, j) + 1/2) / size inside its
//     trust region; out (first direction, converged).
//   mode 1, estimator: Bernoulli trials from the conditional space C(u*) of the target
//     (Eq. 9) until one finds it; out (K / P(C), K, P(C), finished).
#define MANIFOLD_TRUST_REGION 1
#include "lib/bvh.glsl"
#include "lib/manifold/partition.glsl"
#include "lib/manifold/sms.glsl"
#include "lib/rng.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

vec4 cfg(int i) { return imageLoad(inputImage, ivec2(i, 0)); }

uint test_rows[32];
bool partition_tile_in_set(uint set, uvec2 tile, uint tiles) {
    return ((test_rows[tile.y] >> tile.x) & 1u) != 0u;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    for (int r = 0; r < 32; ++r) {
        vec4 m = cfg(8 + r);
        test_rows[r] = uint(m.x) | (uint(m.y) << 16u);
    }
    vec3 x0 = cfg(0).xyz, ng0 = cfg(1).xyz, y = cfg(2).xyz, ny = cfg(3).xyz;
    uint mode = uint(cfg(0).w);
    ManifoldPartition part;
    part.tiles = uint(cfg(1).w);
    part.set = 0u;
    part.set_size = uint(cfg(6).w);
    part.alpha = cfg(2).w;
    ManifoldSettings ms;
    ms.constraint = MANIFOLD_CONSTRAINT_ANGLE_DIFFERENCE;
    ms.max_iterations = uint(cfg(3).w);
    ms.solver_threshold = cfg(7).w;
    ms.min_segment = 1e-4;
    ms.step_control = MANIFOLD_STEP_REPROJECTION;
    ms.max_chain = max(uint(cfg(6).x), 1u);
    ManifoldSeedSpace space = manifold_seed_space(x0, ng0, cfg(4));
    vec3 target = cfg(5).xyz;
    uint shape = uint(cfg(5).w);
    Rng rng = rng_init(pixel, 0u, 0x7E57u);

    vec2 u_star;
    bool have_target = manifold_seed_coords(space, target, u_star);
    uvec2 centre = manifold_seed_tile(u_star, part.tiles);
    uint in_region = partition_region_in_set(part, centre);
    float p_c = partition_region_probability(part, in_region);
    uint trials = 0u;
    bool finished = false;
    ManifoldTrial tr;
    tr.phase = TRIAL_FAILED;
    bool pending = false;
    for (;;) {
        if (!manifold_trial_running(tr)) {
            if (pending) {
                pending = false;
                bool ok = tr.phase == TRIAL_CONVERGED;
                if (mode == 0u) break;
                if (ok && manifold_same_solution(manifold_trial_direction(tr), target, 1e-5)) {
                    finished = true;
                    break;
                }
            }
            if (bvh_iterations > 60000u || !have_target && mode == 1u) break;
            vec2 u = mode == 0u ? (vec2(pixel) + 0.5) / vec2(pc.frameSize)
                                : partition_trial_seed(part, centre, in_region, rng);
            tr = manifold_trial_start(x0, ng0, y, ny, vec3(1, 0, 0), vec3(0, 0, 1), false, false,
                                      x0 + manifold_seed_direction(space, u));
            tr.space = space;
            tr.tiles = part.tiles;
            tr.region = manifold_seed_tile(u, part.tiles);
            tr.first_shape = shape;
            trials += 1u;
            pending = true;
        }
        Hit hit;
        bool found = trace_closest(tr.ray_o, tr.ray_d, tr.ray_tmin, tr.ray_tmax, BVH_MASK_ALL, hit);
        manifold_trial_advance(tr, found, hit, ms);
    }
    vec4 out_value;
    if (mode == 0u) {
        bool ok = tr.phase == TRIAL_CONVERGED;
        out_value = vec4(ok ? manifold_trial_direction(tr) : vec3(0.0), ok ? 1.0 : 0.0);
    } else {
        out_value = vec4(float(trials) / p_c, float(trials), p_c, finished ? 1.0 : 0.0);
    }
    imageStore(outputImage, ivec2(pixel), out_value);
}
