#version 460
// Test kernel (passes/common/tests/test_common_passes.cpp): output = input (when connected) + step.
layout(local_size_x = 8, local_size_y = 8) in;
#if HAS_INPUT
layout(rgba32f) uniform readonly image2D inputImage;
#endif
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    float step;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    vec4 v = vec4(float(p.x), float(p.y), 0.0, 0.0);
#if HAS_INPUT
    v = imageLoad(inputImage, p);
#endif
    imageStore(outputImage, p, v + pc.step);
}
