// Screened Poisson reconstruction (PoissonReconstruct): the buffers and the operator every
// kernel of the solver shares.
//
// The problem is min_x ||W (b - P x)||^2 with P x = [alpha x; D_x x; D_y x], forward
// differences and Neumann boundaries (the last column's x-gradients and the last row's
// y-gradients are not equations). Its normal equations A x = P^T W^2 b are a weighted
// graph Laplacian plus a diagonal:
//   (A x)_i = s_i x_i + sum over the 4-neighbours n of w_in (x_i - x_n),
// with s_i = alpha^2 W^2 of the primal row and w_in = W^2 of the gradient row between i and
// n. Weights are stored per pixel as (s, w to the right, w below, 0); a missing edge has
// weight 0. Every multigrid level has the same form, so one operator serves all of them.
#ifndef POISSON_COMMON_GLSL
#define POISSON_COMMON_GLSL

#extension GL_KHR_shader_subgroup_arithmetic : require

// All vectors (solution, residual, CG directions, multigrid levels) live in one buffer at
// offsets the pass computes; RGB are solved at once, one CG per channel, in a vec4.
layout(std430) buffer PoissonVectors { vec4 vec[]; };
layout(std430) buffer PoissonWeights { vec4 weight[]; };

// One record per solver step: the reductions write it, the next kernels read their CG
// scalars from it, the host reads it back as the residual history.
struct PoissonStep {
    vec4 rr;   // r.r per channel
    vec4 rz;   // r.z (z = M^-1 r; = rr without a preconditioner)
    vec4 pAp;  // p.Ap
    vec4 bb;   // b.b of this linear solve (its first step only)
    uvec4 info;  // x: 1 while the solve is running (0 once converged or never reached)
};
layout(std430) buffer PoissonHistory { PoissonStep steps[]; };

// Kernels of step `slot` do nothing once that step's solve has converged; NO_SLOT always runs.
#define POISSON_NO_SLOT 0xffffffffu
bool poisson_active(uint slot) { return slot == POISSON_NO_SLOT || steps[slot].info.x != 0u; }

uint poisson_index(ivec2 p, uvec2 size) { return uint(p.y) * size.x + uint(p.x); }

// The diagonal of A at p.
float poisson_diagonal(uint wo, uvec2 size, ivec2 p) {
    uint i = poisson_index(p, size);
    vec4 wc = weight[wo + i];
    float d = wc.x + wc.y + wc.z;
    if (p.x > 0) d += weight[wo + i - 1u].y;
    if (p.y > 0) d += weight[wo + i - size.x].z;
    return d;
}

// sum over neighbours of w_in x_n (the off-diagonal part of A x, negated).
vec4 poisson_neighbours(uint xo, uint wo, uvec2 size, ivec2 p) {
    uint i = poisson_index(p, size);
    vec4 wc = weight[wo + i];
    vec4 acc = vec4(0.0);
    if (uint(p.x) + 1u < size.x) acc += wc.y * vec[xo + i + 1u];
    if (uint(p.y) + 1u < size.y) acc += wc.z * vec[xo + i + size.x];
    if (p.x > 0) acc += weight[wo + i - 1u].y * vec[xo + i - 1u];
    if (p.y > 0) acc += weight[wo + i - size.x].z * vec[xo + i - size.x];
    return acc;
}

vec4 poisson_apply(uint xo, uint wo, uvec2 size, ivec2 p) {
    uint i = poisson_index(p, size);
    return poisson_diagonal(wo, size, p) * vec[xo + i] - poisson_neighbours(xo, wo, size, p);
}

// CG step size and direction update per channel; a channel whose scalars vanished (converged
// exactly, or the unused alpha channel) stands still instead of dividing by zero.
vec4 poisson_ratio(vec4 num, vec4 den) {
    return mix(vec4(0.0), num / max(den, vec4(1e-30)), greaterThan(den, vec4(0.0)));
}

// Partial sums of up to two vec4 dot products, one pair per subgroup (subgroupAdd), with no
// barrier: on lavapipe, where every barrier is expensive, a shared-memory tree per workgroup
// cost 60 % of a CG step. Workgroup g's subgroups own pairs 16 g .. 16 g + 64 / subgroup size
// - 1; the reduce kernel sums them in a fixed order, so the solve is deterministic on a
// device. Every invocation of the dispatch must call it.
#define POISSON_PAIRS_PER_GROUP 16u
layout(std430) buffer PoissonPartials { vec4 partial[]; };
void poisson_group_sum(vec4 a, vec4 b) {
    vec4 sa = subgroupAdd(a), sb = subgroupAdd(b);
    if (subgroupElect()) {
        uint g = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
        uint pair = g * POISSON_PAIRS_PER_GROUP + gl_SubgroupID;
        partial[2u * pair] = sa;
        partial[2u * pair + 1u] = sb;
    }
}

#endif
