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
    uvec4 state;  // (pixel.x, pixel.y, frame ^ seed mix, counter)
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

uint rng_next_uint(inout Rng r) {
    r.state.w++;
    return pcg4d(r.state).x;
}

// Uniform in [0, 1): top 24 bits so the result is exactly representable.
float rng_next(inout Rng r) { return float(rng_next_uint(r) >> 8) * (1.0 / 16777216.0); }
vec2 rng_next2(inout Rng r) {
    r.state.w++;
    uvec4 h = pcg4d(r.state);
    return vec2(h.xy >> 8) * (1.0 / 16777216.0);
}

#endif
