#version 460
// PoissonReconstruct: sums the workgroup partials (in a fixed order) into the fields of one
// step record, and decides whether the solve goes on: it stops once every channel's residual
// is below tolerance^2 b.b (never with tolerance 0, unless the residual is exactly zero).
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 256) in;
layout(push_constant) uniform Params {
    uint groups;      // number of partial pairs
    uint slot;        // step record written
    uint gateSlot;    // the record whose info.x gates this reduction (POISSON_NO_SLOT: none)
    uint solveSlot;   // the first record of this linear solve (its bb)
    uint fieldA;      // FIELD_* for the first partial
    uint fieldB;      // FIELD_* for the second partial
    float tolerance;
    uint levels;      // multigrid levels (entries of the dispatch arguments)
} pc;

// The dispatch arguments of the next steps' kernels (see PoissonReconstructPass.cpp): the full
// group counts while the solve runs, zero groups once it has converged.
#define POISSON_HALF_ARGS 32u  // + level: half the columns (red-black sweeps)
#define POISSON_REDUCE_ARGS 64u
layout(std430) buffer PoissonDispatch { uvec4 dispatchArgs[]; };
layout(std430) readonly buffer PoissonDispatchFull { uvec4 fullArgs[]; };

#define FIELD_NONE 0u
#define FIELD_RR 1u     // r.r; also decides info.x
#define FIELD_RZ 2u
#define FIELD_PAP 3u
#define FIELD_BB 4u
#define FIELD_RR_RZ 5u  // r.r, used as r.z too (no preconditioner)

shared vec4 sums[2][256];

void store(uint field, vec4 v) {
    if (field == FIELD_RR || field == FIELD_RR_RZ) {
        steps[pc.slot].rr = v;
        vec4 bb = pc.solveSlot == pc.slot ? sums[1][0] : steps[pc.solveSlot].bb;
        bool going = any(greaterThan(v.rgb, pc.tolerance * pc.tolerance * bb.rgb));
        steps[pc.slot].info = uvec4(going ? 1u : 0u, 0u, 0u, 0u);
        for (uint l = 0u; l < pc.levels; ++l) {
            dispatchArgs[l] = going ? fullArgs[l] : uvec4(0u);
            dispatchArgs[POISSON_HALF_ARGS + l] = going ? fullArgs[POISSON_HALF_ARGS + l] : uvec4(0u);
        }
        dispatchArgs[POISSON_REDUCE_ARGS] = going ? fullArgs[POISSON_REDUCE_ARGS] : uvec4(0u);
    }
    if (field == FIELD_RZ || field == FIELD_RR_RZ) steps[pc.slot].rz = v;
    if (field == FIELD_PAP) steps[pc.slot].pAp = v;
    if (field == FIELD_BB) steps[pc.slot].bb = v;
}

void main() {
    if (!poisson_active(pc.gateSlot)) return;
    uint t = gl_LocalInvocationID.x;
    vec4 a = vec4(0.0), b = vec4(0.0);
    // The stencil kernels' workgroups have 64 invocations: 64 / subgroup size pairs each.
    uint perGroup = min((64u + gl_SubgroupSize - 1u) / gl_SubgroupSize, POISSON_PAIRS_PER_GROUP);
    for (uint g = t; g < pc.groups; g += 256u)
        for (uint s = 0u; s < perGroup; ++s) {
            uint pair = g * POISSON_PAIRS_PER_GROUP + s;
            a += partial[2u * pair];
            b += partial[2u * pair + 1u];
        }
    sums[0][t] = a;
    sums[1][t] = b;
    barrier();
    for (uint s = 128u; s > 0u; s >>= 1) {
        if (t < s) {
            sums[0][t] += sums[0][t + s];
            sums[1][t] += sums[1][t + s];
        }
        barrier();
    }
    if (t == 0u) {
        // b.b first: the r.r of a solve's first step compares against it.
        store(pc.fieldB, sums[1][0]);
        store(pc.fieldA, sums[0][0]);
    }
}
