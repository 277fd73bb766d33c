// The rules ReSTIR PT's candidate generation (generation.glsl) and its shifts
// (hybrid_shift.glsl) share, so that both pick the same reconnection vertex and replay the same
// random numbers (Lin et al. 2022, Sec. 6.2):
//
// Reconnection vertex (hybrid shift): the first x_k, k >= 2, such that x_{k-1} and x_k are both
// rough (no delta lobe, alpha > rough_threshold; the last vertex of a path counts as rough) and
// |x_k - x_{k-1}| >= dist_threshold. The offset path must pick the same k (no earlier pair
// qualifies, y_{k-1} rough, segment long enough), else the shift is not a bijection and is
// rejected.
#ifndef LOOM_RESTIR_PATH_RULES_GLSL
#define LOOM_RESTIR_PATH_RULES_GLSL

#include "lib/bsdf.glsl"
#include "lib/restir/reservoir.glsl"
#include "lib/rng.glsl"

// Vertex classification for the reconnection criteria: diffuse, or linear roughness sqrt(alpha)
// above the threshold (the roughness Lin et al.'s Falcor code compares with 0.2, alpha > 0.04).
// Materials with a delta lobe (smooth coatings, glass) never count, whichever lobe was sampled.
bool restir_vertex_rough(Material m, float threshold) {
    uint flags = bsdf_flags(m);
    if ((flags & BSDF_DELTA) != 0u || (flags & (BSDF_DIFFUSE | BSDF_GLOSSY)) == 0u) return false;
    return material_type(m) == MATERIAL_DIFFUSE || sqrt(material_alpha(m)) > threshold;
}

// Is (x_{k-1}, x_k) a reconnection pair under the settings' shift?
bool restir_reconnectable(RestirSettings cfg, uint k, bool rough_prev, bool rough_k, float dist) {
    if (cfg.shift == SHIFT_REPLAY) return false;
    if (cfg.shift == SHIFT_RECONNECTION) return k == 2u && rough_prev && rough_k;
    return rough_prev && rough_k && dist >= cfg.dist_threshold;
}

// The random numbers of vertex x_j: counters 4j+1 .. 4j+4 of the replay stream, the same for
// the path's generation and every replay of it.
void restir_vertex_randoms(uvec4 seed, uint j, out vec3 u_light, out vec3 u_bsdf) {
    Rng r = rng_from_seed(seed);
    r.state.w = 4u * j;
    u_light = vec3(rng_next2(r), rng_next(r));
    u_bsdf = vec3(rng_next(r), rng_next2(r));
}

#endif
