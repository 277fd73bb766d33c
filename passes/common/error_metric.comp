#version 460
// ErrorMetric, stage 1: per-pixel error and its false-colour image.
#include "lib/color.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform readonly image2D referenceImage;
layout(r32f) uniform writeonly image2D perPixelImage;
layout(rgba32f) uniform writeonly image2D errorImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint metric;  // METRIC_MSE, METRIC_RELMSE, METRIC_RMSE, METRIC_MAPE
    float epsilon;
    float falseColorMax;
    uint logScale;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    vec3 x = imageLoad(inputImage, p).rgb;
    vec3 r = imageLoad(referenceImage, p).rgb;
    vec3 d = x - r;
    vec3 e;
    if (pc.metric == METRIC_RELMSE) e = d * d / (r * r + pc.epsilon);
    else if (pc.metric == METRIC_MAPE) e = abs(d) / (abs(r) + pc.epsilon);
    else e = d * d;
    float v = (e.r + e.g + e.b) / 3.0;
    imageStore(perPixelImage, p, vec4(v));
    float t = max(v, 0.0) / pc.falseColorMax;
    if (pc.logScale != 0u) t = log(1.0 + 9.0 * t) / log(10.0);
    imageStore(errorImage, p, vec4(colormap_jet(t), 1.0));
}
