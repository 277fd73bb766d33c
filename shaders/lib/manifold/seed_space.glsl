// The seed space of sample-space-partitioned SMS (Hong et al. 2025 Sec. 4.1): u in [0,1)^2
// parameterises the first specular vertex x1 of a chain from a receiver point x0 by direction
// (a surface parameterisation can be discontinuous, their fn. 2). u maps by Shirley-Chiu's
// concentric disk onto an equal-area cone: the cone around the direction to the caster's
// bounding sphere when x0 is outside it, else the hemisphere on the side x0 is seen from. The
// unit square is cut into N x N tiles; a walk seeded in tile t may not leave the trust region
// R(t), the 3 x 3 tiles around t with periodic wrapping.
#ifndef LOOM_MANIFOLD_SEED_SPACE_GLSL
#define LOOM_MANIFOLD_SEED_SPACE_GLSL

#include "lib/sampling.glsl"

struct ManifoldSeedSpace {
    vec3 axis;
    float cos_max;  // the cone's half-angle cosine (0: hemisphere)
};

// bound: the caster's world-space bounding sphere (centre, radius); ng0: x0's geometric normal
// on the side it is seen from.
ManifoldSeedSpace manifold_seed_space(vec3 x0, vec3 ng0, vec4 bound) {
    ManifoldSeedSpace ss;
    vec3 d = bound.xyz - x0;
    float dist = length(d);
    if (dist > bound.w * 1.001) {
        ss.axis = d / dist;
        ss.cos_max = sqrt(max(0.0, 1.0 - (bound.w * bound.w) / (dist * dist)));
    } else {
        ss.axis = ng0;
        ss.cos_max = 0.0;
    }
    return ss;
}

vec3 manifold_seed_direction(ManifoldSeedSpace ss, vec2 u) {
    vec2 p = sample_disk_concentric(u);
    float r2 = dot(p, p);
    float cos_t = 1.0 - r2 * (1.0 - ss.cos_max);
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    vec2 xy = r2 > 0.0 ? p * (sin_t * inversesqrt(r2)) : vec2(0.0);
    vec3 t, b;
    orthonormal_basis(ss.axis, t, b);
    return xy.x * t + xy.y * b + cos_t * ss.axis;
}

// The inverse map; false when w lies outside the cone.
bool manifold_seed_coords(ManifoldSeedSpace ss, vec3 w, out vec2 u) {
    vec3 t, b;
    orthonormal_basis(ss.axis, t, b);
    float cos_t = dot(w, ss.axis);
    u = vec2(0.5);
    if (cos_t < ss.cos_max) return false;
    float r = sqrt(clamp((1.0 - cos_t) / max(1.0 - ss.cos_max, 1e-12), 0.0, 1.0));
    vec2 xy = vec2(dot(w, t), dot(w, b));
    float s = length(xy);
    u = disk_concentric_inverse(s > 0.0 ? xy * (r / s) : vec2(0.0));
    return true;
}

uvec2 manifold_seed_tile(vec2 u, uint tiles) {
    return min(uvec2(u * float(tiles)), uvec2(tiles - 1u));
}

// Distinct tiles of a trust region: 9, or all of them for N < 3.
uint manifold_region_size(uint tiles) { return tiles >= 3u ? 9u : tiles * tiles; }

// The j-th tile (j < manifold_region_size) of the region around centre.
uvec2 manifold_region_tile(uvec2 centre, uint j, uint tiles) {
    if (tiles < 3u) return uvec2(j % tiles, j / tiles);
    ivec2 o = ivec2(int(j % 3u) - 1, int(j / 3u) - 1);
    return uvec2((ivec2(centre) + o + int(tiles)) % int(tiles));
}

bool manifold_region_contains(uvec2 centre, uvec2 tile, uint tiles) {
    ivec2 n = ivec2(tiles), d = (ivec2(tile) - ivec2(centre) + n) % n;
    return all(lessThanEqual(min(d, n - d), ivec2(1)));
}

#endif
