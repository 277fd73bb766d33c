#version 460
// PoissonReconstruct: the solution as an image (alpha 1).
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint xOffset;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    imageStore(outputImage, p, vec4(vec[pc.xOffset + poisson_index(p, pc.frameSize)].rgb, 1.0));
}
