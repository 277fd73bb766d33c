#version 460
// Accumulate: running mean and per-pixel sample variance (Welford 1962).
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform image2D meanImage;   // persistent
layout(rgba32f) uniform image2D m2Image;     // persistent: sum of squared deviations
layout(rgba32f) uniform writeonly image2D outputImage;
#if HAS_VARIANCE
layout(rgba32f) uniform writeonly image2D varianceImage;
#endif
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint count;       // frames already in the mean (0 = reset)
    uint enabled;     // 0: pass the input through (still reporting count 1)
    uint frozen;      // maxFrames reached: report the stored mean and variance unchanged
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    vec4 mean = vec4(0.0), m2 = vec4(0.0);
    float n = 1.0;
    if (pc.frozen != 0u) {
        mean = imageLoad(meanImage, p);
        m2 = imageLoad(m2Image, p);
        n = float(pc.count);
    } else {
        vec4 x = imageLoad(inputImage, p);
        if (pc.enabled != 0u && pc.count > 0u) {
            mean = imageLoad(meanImage, p);
            m2 = imageLoad(m2Image, p);
            n = float(pc.count) + 1.0;
        }
        vec4 delta = x - mean;
        mean += delta / n;
        m2 += delta * (x - mean);
        imageStore(meanImage, p, mean);
        imageStore(m2Image, p, m2);
    }
    imageStore(outputImage, p, mean);
#if HAS_VARIANCE
    vec3 variance = n > 1.0 ? m2.rgb / (n - 1.0) : vec3(0.0);
    imageStore(varianceImage, p, vec4(variance, n));
#endif
}
