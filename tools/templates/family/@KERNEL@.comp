#version 460
// @PASS@ (passes/@FAMILY@/@PASS@Pass.cpp). Members are filled by name from the pass's
// declared parameters; MODE_SCALE / MODE_SQUARE are generated from its `mode` enum.
layout(local_size_x = 8, local_size_y = 8) in;

layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;

layout(push_constant) uniform Params {
    uvec2 frameSize;
    float gain;
    uint mode;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    vec4 v = imageLoad(inputImage, p);
    if (pc.mode == MODE_SQUARE) v *= v;
    imageStore(outputImage, p, pc.gain * v);
}
