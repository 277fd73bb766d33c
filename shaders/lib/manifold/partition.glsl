// Seed distributions of sample-space-partitioned SMS (Hong et al. 2025 Sec. 4.1-4.2): the
// initial seed mixture of a tile set I and the whole space (Eq. 7), the probability of the
// conditional space C(u*) = R(u*) (Eq. 8) and Bernoulli-trial seeds drawn from the mixture
// conditioned on C(u*) (Eq. 9). The estimator's weight K / P(C(u*)) has mean 1 / P'(x*).
//
// The tile set is the includer's: it defines
//   bool partition_tile_in_set(uint set, uvec2 tile, uint tiles);
// (PartitionedSMS: a slot of ManifoldPrior, lib/manifold/prior.glsl; tests: a mask).
#ifndef LOOM_MANIFOLD_PARTITION_GLSL
#define LOOM_MANIFOLD_PARTITION_GLSL

#include "lib/manifold/seed_space.glsl"
#include "lib/rng.glsl"

bool partition_tile_in_set(uint set, uvec2 tile, uint tiles);

struct ManifoldPartition {
    uint tiles;     // N
    uint set;       // the includer's handle of I
    uint set_size;  // #I at N (0: no prior, the mixture is uniform)
    float alpha;    // the prior's weight in Eq. 7
};

// #I at partition N.
uint partition_set_size(uint set, uint tiles) {
    uint n = 0u;
    for (uint y = 0u; y < tiles; ++y)
        for (uint x = 0u; x < tiles; ++x) n += partition_tile_in_set(set, uvec2(x, y), tiles) ? 1u : 0u;
    return n;
}

float partition_alpha(ManifoldPartition p) { return p.set_size > 0u ? p.alpha : 0.0; }

// Eq. 7: with probability alpha a tile uniform in I, else uniform in [0,1)^2; uniform in the
// tile. Seed density alpha N^2 / #I on I's tiles + (1 - alpha).
vec2 partition_initial_seed(ManifoldPartition p, inout Rng rng) {
    vec2 r = rng_next2(rng);
    float a = partition_alpha(p);
    if (r.x >= a) return rng_next2(rng);
    uint n = min(uint(r.x / a * float(p.set_size)), p.set_size - 1u);
    uvec2 t = uvec2(0u);
    for (uint y = 0u; y < p.tiles; ++y)
        for (uint x = 0u; x < p.tiles; ++x)
            if (partition_tile_in_set(p.set, uvec2(x, y), p.tiles)) {
                if (n == 0u) t = uvec2(x, y);
                --n;  // wraps past 0: no later tile matches
            }
    return (vec2(t) + rng_next2(rng)) / float(p.tiles);
}

// #(I n C(u*)), C(u*) the trust region around the tile of u*.
uint partition_region_in_set(ManifoldPartition p, uvec2 centre) {
    uint n = 0u;
    if (p.set_size == 0u) return 0u;
    for (uint j = 0u; j < manifold_region_size(p.tiles); ++j)
        n += partition_tile_in_set(p.set, manifold_region_tile(centre, j, p.tiles), p.tiles) ? 1u : 0u;
    return n;
}

// Eq. 8: P(C) = alpha #(I n C) / #I + (1 - alpha) #C / N^2, #C the region's distinct tiles.
float partition_region_probability(ManifoldPartition p, uint in_region) {
    float a = partition_alpha(p);
    float p_i = p.set_size > 0u ? float(in_region) / float(p.set_size) : 0.0;
    return a * p_i + (1.0 - a) * float(manifold_region_size(p.tiles)) / float(p.tiles * p.tiles);
}

// Eq. 9: the Eq. 7 mixture conditioned on C(u*): with probability
// alpha' = alpha #(I n C) / #I / P(C) a tile uniform in I n C, else a tile uniform in C.
vec2 partition_trial_seed(ManifoldPartition p, uvec2 centre, uint in_region, inout Rng rng) {
    uint size = manifold_region_size(p.tiles);
    float a_prime = in_region > 0u ? partition_alpha(p) * float(in_region) / float(p.set_size) /
                                         partition_region_probability(p, in_region)
                                   : 0.0;
    vec2 r = rng_next2(rng);
    uvec2 t = manifold_region_tile(centre, min(uint(r.y * float(size)), size - 1u), p.tiles);
    if (r.x < a_prime) {
        uint n = min(uint(r.x / a_prime * float(in_region)), in_region - 1u);
        for (uint j = 0u; j < size; ++j) {
            uvec2 tj = manifold_region_tile(centre, j, p.tiles);
            if (partition_tile_in_set(p.set, tj, p.tiles)) {
                if (n == 0u) t = tj;
                --n;
            }
        }
    }
    return (vec2(t) + rng_next2(rng)) / float(p.tiles);
}

#endif
