#version 460
// PoissonReconstruct, multigrid: one colour of a red-black Gauss-Seidel sweep on one level,
// x_i = (b_i + sum_n w_in x_n) / A_ii for the pixels with (x + y) % 2 == colour. With
// zeroGuess (the level's first sweep from x = 0) the other colour is set to 0 and no x is
// read, so the level needs no clearing. Dispatched over half the level's columns: each
// invocation owns the pixel of this colour in its pair of columns.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 levelSize;
    uint xOffset;
    uint bOffset;
    uint wOffset;
    uint colour;
    uint zeroGuess;
    uint residual;   // 1: write r = b - A x instead of sweeping (see below)
    uint rOffset;
    uint slot;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 pair = ivec2(gl_GlobalInvocationID.xy);
    int odd = int((pc.colour + uint(pair.y)) & 1u);
    ivec2 p = ivec2(2 * pair.x + odd, pair.y);  // (p.x + p.y) % 2 == colour
    ivec2 other = ivec2(2 * pair.x + 1 - odd, pair.y);
    if (pc.residual != 0u) {
        // The residual after a sweep that ended with the other colour: there every equation
        // was just solved exactly, so its residual is 0 and only this colour's half is computed
        // (and the restriction skips the zeros).
        if (all(lessThan(uvec2(other), pc.levelSize)))
            vec[pc.rOffset + poisson_index(other, pc.levelSize)] = vec4(0.0);
        if (any(greaterThanEqual(uvec2(p), pc.levelSize))) return;
        uint i = poisson_index(p, pc.levelSize);
        vec[pc.rOffset + i] = vec[pc.bOffset + i] - poisson_apply(pc.xOffset, pc.wOffset, pc.levelSize, p);
        return;
    }
    if (pc.zeroGuess != 0u && all(lessThan(uvec2(other), pc.levelSize)))
        vec[pc.xOffset + poisson_index(other, pc.levelSize)] = vec4(0.0);
    if (any(greaterThanEqual(uvec2(p), pc.levelSize))) return;
    uint i = poisson_index(p, pc.levelSize);
    if (pc.zeroGuess != 0u) {
        vec[pc.xOffset + i] = vec[pc.bOffset + i] / poisson_diagonal(pc.wOffset, pc.levelSize, p);
        return;
    }
    vec[pc.xOffset + i] = (vec[pc.bOffset + i] + poisson_neighbours(pc.xOffset, pc.wOffset, pc.levelSize, p)) /
                          poisson_diagonal(pc.wOffset, pc.levelSize, p);
}
