#version 460
// Reservoir splatting, step 3 of the scatter: every landed splat writes its source pixel into
// its destination's range, at its rank.
#include "passes/reservoir_splat/splat_buffers.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    uvec2 q = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(q, pc.frameSize))) return;
    uint idx = q.y * pc.frameSize.x + q.x;
    SplatRecord rec = splat_records[idx];
    if (rec.dst < SPLAT_OCCLUDED) splat_lists[splat_ranges[rec.dst].y + rec.slot] = idx;
}
