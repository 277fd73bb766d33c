#version 460
// ManifoldPrior's debug view: the tile set I of one listed pair of the block holding
// debugPixel, its 32 x 32 fine tiles stretched over the image (set: white; not set: dark
// blue; the block lists fewer pairs than debugSlot + 1: black).
#include "lib/manifold/prior.glsl"

layout(push_constant) uniform Params {
    uvec2 frameSize;
    vec2 debugPixel;
    uint debugSlot;
} pc;

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D tileImage;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uvec2 at = min(uvec2(max(pc.debugPixel, vec2(0.0))), pc.frameSize - 1u);
    uint block = prior_block(at, pc.frameSize);
    vec3 c = vec3(0.0);
    if (pc.debugSlot < prior_list_length(block)) {
        uvec2 t = min(pixel * PRIOR_FINE_TILES / pc.frameSize, uvec2(PRIOR_FINE_TILES - 1u));
        // Row 0 of the seed space at the bottom of the image.
        t.y = PRIOR_FINE_TILES - 1u - t.y;
        bool set = prior_tile_set(prior_slot_base(block, pc.debugSlot), t, PRIOR_FINE_TILES);
        c = set ? vec3(1.0) : vec3(0.02, 0.03, 0.12);
    }
    imageStore(tileImage, ivec2(pixel), vec4(c, 1.0));
}
