#version 460
// ToneMap: exposure (EV), operator, optional sRGB encode.
#include "lib/color.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    float exposureScale;  // 2^exposure
    uint operator;        // OPERATOR_CLAMP, OPERATOR_REINHARD, OPERATOR_ACES
    uint srgb;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    vec4 c = imageLoad(inputImage, p);
    vec3 v = c.rgb * pc.exposureScale;
    if (pc.operator == OPERATOR_REINHARD) v = tonemap_reinhard(v);
    else if (pc.operator == OPERATOR_ACES) v = tonemap_aces(v);
    v = clamp(v, 0.0, 1.0);
    if (pc.srgb != 0u) v = linear_to_srgb(v);
    imageStore(outputImage, p, vec4(v, 1.0));
}
