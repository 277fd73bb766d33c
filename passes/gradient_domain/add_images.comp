#version 460
// output = a + b (rgb; alpha 1). A ComputePass kernel: gradient-domain graphs add the emission
// seen at the primary hit back to the reconstructed image (graphs/gpt.json).
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D aImage;
layout(rgba32f) uniform readonly image2D bImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    imageStore(outputImage, p, vec4(imageLoad(aImage, p).rgb + imageLoad(bImage, p).rgb, 1.0));
}
