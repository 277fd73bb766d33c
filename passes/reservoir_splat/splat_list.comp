#version 460
// Reservoir splatting, step 3 of the scatter: every landed splat writes its source pixel into
// its destination's range, at its rank (entries are record indices: pixel and time partition).
#include "passes/reservoir_splat/splat_buffers.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    uvec2 q = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(q, pc.frameSize))) return;
    uint idx = q.y * pc.frameSize.x + q.x;
    for (uint n = 0u; n < MAX_TIME_PARTITIONS; ++n) {
        uint e = idx * MAX_TIME_PARTITIONS + n;
        SplatRecord rec = splat_records[e];
        if (rec.dst < SPLAT_OCCLUDED) splat_lists[splat_ranges[rec.dst].y + rec.slot] = e;
    }
}
