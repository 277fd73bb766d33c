#version 460
// PoissonReconstruct, multigrid: one colour of a red-black Gauss-Seidel sweep on one level,
// x_i = (b_i + sum_n w_in x_n) / A_ii for the pixels with (x + y) % 2 == colour. With
// zeroGuess (the level's first sweep from x = 0) the other colour is set to 0 and no x is
// read, so the level needs no clearing.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params {
    uvec2 levelSize;
    uint xOffset;
    uint bOffset;
    uint wOffset;
    uint colour;
    uint zeroGuess;
    uint slot;
} pc;

void main() {
    if (!poisson_active(pc.slot)) return;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.levelSize))) return;
    uint i = poisson_index(p, pc.levelSize);
    bool mine = uint(p.x + p.y) % 2u == pc.colour;
    if (pc.zeroGuess != 0u) {
        vec[pc.xOffset + i] =
            mine ? vec[pc.bOffset + i] / poisson_diagonal(pc.wOffset, pc.levelSize, p) : vec4(0.0);
        return;
    }
    if (!mine) return;
    vec[pc.xOffset + i] = (vec[pc.bOffset + i] + poisson_neighbours(pc.xOffset, pc.wOffset, pc.levelSize, p)) /
                          poisson_diagonal(pc.wOffset, pc.levelSize, p);
}
