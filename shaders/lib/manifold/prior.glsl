// The per-frame prior of sample-space-partitioned SMS (Hong et al. 2025 Sec. 4.2): for each
// B x B pixel block, per light-caster pair, the set I of seed-space tiles in which presampled
// walks found a solution. Tiles are recorded at the finest resolution, 32 x 32 (one 32-bit
// word per tile row); a coarser partition N (a divisor of 32) reads a coarse tile as set when
// any of its fine tiles is.
//
// Layout of ManifoldPrior (uints): per block (row-major, ceil(width / PRIOR_BLOCK) per row)
// PRIOR_SLOTS slots of PRIOR_SLOT_WORDS: a key (pair + 1; 0 = free) and 32 rows. Slots fill in
// order (a free slot ends the list). Overflow rule: a solution whose pair finds no free slot
// is dropped (and counted); the estimator's pdf only needs the I it reads, so a lost pair
// costs variance, not bias. Sizes mirrored by ManifoldPriorPass.cpp.
#ifndef LOOM_MANIFOLD_PRIOR_GLSL
#define LOOM_MANIFOLD_PRIOR_GLSL

#define PRIOR_BLOCK 16u  // B: pixels per block side
#define PRIOR_SLOTS 8u   // pairs a block lists
#define PRIOR_FINE_TILES 32u
#define PRIOR_SLOT_WORDS 33u

layout(std430) buffer ManifoldPrior { uint prior_words[]; };

uint prior_block(uvec2 pixel, uvec2 frame_size) {
    uint blocks_x = (frame_size.x + PRIOR_BLOCK - 1u) / PRIOR_BLOCK;
    return (pixel.y / PRIOR_BLOCK) * blocks_x + pixel.x / PRIOR_BLOCK;
}

uint prior_slot_base(uint block, uint slot) { return (block * PRIOR_SLOTS + slot) * PRIOR_SLOT_WORDS; }

// Records that pair's walks find a solution in fine tile t; false on overflow.
bool prior_insert(uint block, uint pair, uvec2 t) {
    for (uint s = 0u; s < PRIOR_SLOTS; ++s) {
        uint base = prior_slot_base(block, s);
        uint key = atomicCompSwap(prior_words[base], 0u, pair + 1u);
        if (key == 0u || key == pair + 1u) {
            atomicOr(prior_words[base + 1u + t.y], 1u << t.x);
            return true;
        }
    }
    return false;
}

// Pairs listed for a block.
uint prior_list_length(uint block) {
    uint n = 0u;
    while (n < PRIOR_SLOTS && prior_words[prior_slot_base(block, n)] != 0u) ++n;
    return n;
}

uint prior_slot_pair(uint block, uint slot) { return prior_words[prior_slot_base(block, slot)] - 1u; }

// The slot holding pair, ~0u if none.
uint prior_find(uint block, uint pair, uint length) {
    for (uint s = 0u; s < length; ++s)
        if (prior_words[prior_slot_base(block, s)] == pair + 1u) return s;
    return ~0u;
}

// The slot with the k-th smallest pair of the block's list (k < length): slots fill in the
// order threads arrive, pairs give the list an order that does not depend on it.
uint prior_sorted_slot(uint block, uint k, uint length) {
    for (uint s = 0u; s < length; ++s) {
        uint key = prior_words[prior_slot_base(block, s)], rank = 0u;
        for (uint j = 0u; j < length; ++j) rank += prior_words[prior_slot_base(block, j)] < key ? 1u : 0u;
        if (rank == k) return s;
    }
    return 0u;
}

// Whether coarse tile t of an N x N partition is in the slot's set.
bool prior_tile_set(uint base, uvec2 t, uint tiles) {
    uint f = PRIOR_FINE_TILES / tiles;
    uint mask = f == 32u ? ~0u : ((1u << f) - 1u) << (t.x * f);
    uint rows = 0u;
    for (uint r = t.y * f; r < t.y * f + f; ++r) rows |= prior_words[base + 1u + r];
    return (rows & mask) != 0u;
}

#endif
