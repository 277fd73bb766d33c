// Counter-based random numbers: every sample is a hash of (pixel, frame, seed, counter), so any
// stream can be replayed from its seed (ReSTIR random replay needs this).
#ifndef LOOM_RNG_GLSL
#define LOOM_RNG_GLSL

// Jarzynski & Olano 2020, "Hash Functions for GPU Rendering", pcg4d.
uvec4 pcg4d(uvec4 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    return v;
}

struct Rng {
    uvec4 state;  // (pixel.x, pixel.y, frame ^ seed mix, counter); RNG_SOBOL: see below
};

Rng rng_init(uvec2 pixel, uint frame, uint seed) {
    Rng r;
    r.state = uvec4(pixel, frame * 0x9E3779B9u ^ (seed * 0x85EBCA6Bu + 0x68E31DA4u), 0u);
    return r;
}

// Replay a stream from a stored seed (e.g. a reservoir's path seed).
Rng rng_from_seed(uvec4 seed) {
    Rng r;
    r.state = seed;
    return r;
}

// Owen-scrambled Sobol points, padded (Burley 2020, "Practical Hash-based Owen Scrambling",
// JCGT 9(4); pbrt-v4's PaddedSobolSampler): each draw of a sample is its own dimension, a 1D
// draw the scrambled van der Corput sequence and a 2D draw Sobol's first two dimensions (a
// (0,2)-sequence), each with its own nested uniform scramble and its own shuffle of the sample
// index. Every draw is uniform on its own and draws of one sample are independent (distinct
// dimensions), so estimators stay unbiased; over a pixel's samples each draw is stratified.
// Burley's Laine-Karras-style hash: bit k of the result depends on bits 0..k of x only.
uint rng_laine_karras(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}
// Nested uniform (Owen) scramble of a 32-digit base-2 fraction: digit k flips by a hash of the
// digits before it.
uint rng_owen_scramble(uint x, uint seed) {
    return bitfieldReverse(rng_laine_karras(bitfieldReverse(x), seed));
}
// Sobol's second dimension: direction numbers v_0 = 2^31, v_k = v_{k-1} ^ (v_{k-1} >> 1)
// (primitive polynomial x + 1). Straight-line, so no lane waits on another's index.
uint rng_sobol_dim1(uint i) {
    uint x = 0u, v = 0x80000000u;
    for (uint k = 0u; k < 32u; ++k) {
        x ^= v & (0u - ((i >> k) & 1u));
        v ^= v >> 1u;
    }
    return x;
}
uint rng_hash2(uint a, uint b) { return pcg4d(uvec4(a, b, 0x2545F491u, 0x9E3779B9u)).x; }
float rng_unit(uint x) { return float(x >> 8) * (1.0 / 16777216.0); }

#ifdef RNG_SOBOL
// Kernels compiled with RNG_SOBOL = 1 draw from the padded Sobol sampler: state = (pixel seed,
// sample index, 0, dimension counter); rng_sample_init starts a sample.
Rng rng_sample_init(uvec2 pixel, uint sample_index, uint seed) {
    Rng r;
    r.state = uvec4(pcg4d(uvec4(pixel, seed, 0x51B01u)).x, sample_index, 0u, 0u);
    return r;
}
// Dimension dim of the sample: its scramble seed, and in i the sample index in this
// dimension's own order (the shuffle).
uint rng_sobol_dimension(Rng r, uint dim, out uint i) {
    uint seed = rng_hash2(r.state.x, dim);
    i = rng_owen_scramble(r.state.y, seed);
    return seed;
}
// Sobol's first dimension (van der Corput) at shuffled index i, scrambled.
uint rng_sobol_dim0_scrambled(uint i, uint seed) {
    return rng_owen_scramble(bitfieldReverse(i), rng_hash2(seed, 1u));
}
uint rng_next_uint(inout Rng r) {
    uint i;
#ifdef LOOM_TEST_SOBOL_REUSE_DIMENSION  // a planted bug (test_path_tracer.cpp): the dimension
    uint seed = rng_sobol_dimension(r, r.state.w - 1u, i);  // of the draw before, again
#else
    uint seed = rng_sobol_dimension(r, r.state.w++, i);
#endif
    return rng_sobol_dim0_scrambled(i, seed);
}
float rng_next(inout Rng r) { return rng_unit(rng_next_uint(r)); }
vec2 rng_next2(inout Rng r) {
    uint i;
    uint seed = rng_sobol_dimension(r, r.state.w++, i);
    return vec2(rng_unit(rng_sobol_dim0_scrambled(i, seed)),
                rng_unit(rng_owen_scramble(rng_sobol_dim1(i), rng_hash2(seed, 2u))));
}
#else
uint rng_next_uint(inout Rng r) {
    r.state.w++;
    return pcg4d(r.state).x;
}

// Uniform in [0, 1): top 24 bits so the result is exactly representable.
float rng_next(inout Rng r) { return rng_unit(rng_next_uint(r)); }
vec2 rng_next2(inout Rng r) {
    r.state.w++;
    uvec4 h = pcg4d(r.state);
    return vec2(rng_unit(h.x), rng_unit(h.y));
}
#endif

#endif
