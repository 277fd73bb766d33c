#version 460
// Reservoir splatting, step 2 of the scatter: each pixel takes a range of the index list for
// the splats that landed in it, by one atomic on a global counter. Ranges need no order (an
// ordered prefix sum is not needed); the resampling visits each pixel's entries in source order.
#include "passes/reservoir_splat/splat_buffers.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    uint n = splat_ranges[idx].x;
    splat_ranges[idx].y = n > 0u ? atomicAdd(splat_allocated, n) : 0u;
    if (n > 0u) {
        atomicAdd(splat_pixels_reached, 1u);
        atomicMax(splat_max_per_pixel, n);
    }
}
