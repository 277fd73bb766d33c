#version 460
// Forward differences of an image with the Neumann convention PoissonReconstruct expects:
// dx(p) = x(p + e_x) - x(p), dy(p) = x(p + e_y) - x(p), 0 in the last column / row. A
// ComputePass kernel (graphs/poisson_pt.json): exact gradients of an image, e.g. to
// reconstruct a noisy primal from a cleaner estimate's gradients, or to test a solver.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D dxImage;
layout(rgba32f) uniform writeonly image2D dyImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    vec4 c = imageLoad(inputImage, p);
    vec4 dx = uint(p.x) + 1u < pc.frameSize.x ? imageLoad(inputImage, p + ivec2(1, 0)) - c : vec4(0.0);
    vec4 dy = uint(p.y) + 1u < pc.frameSize.y ? imageLoad(inputImage, p + ivec2(0, 1)) - c : vec4(0.0);
    imageStore(dxImage, p, vec4(dx.rgb, 0.0));
    imageStore(dyImage, p, vec4(dy.rgb, 0.0));
}
