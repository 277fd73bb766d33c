#version 460
// SpecularManifoldSampling, stage 3: the caustic estimate, the full image (path part + caustic)
// and the per-pixel statistics. Estimates that ran out of dispatches count as capped.
#include "passes/sms/sms_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D pathImage;
layout(rgba32f) uniform writeonly image2D colorImage;
#if HAS_CAUSTIC
layout(rgba32f) uniform writeonly image2D causticImage;
#endif
#if HAS_STATS
layout(rgba32f) uniform writeonly image2D statsImage;
#endif

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    SmsPixel st = sms_pixels[sms_pixel_index(pixel)];
    uint status = st.hit.w;
    vec3 caustic = vec3(0.0);
    if (status == SMS_DONE || status == SMS_BIASED) {
        caustic = st.value.rgb;
    } else if (status == SMS_BERNOULLI || status == SMS_FIRST) {
        // Out of dispatches before the solution came back (or before the first walk ended):
        // the trial cap, reached early.
        atomicAdd(sms_capped, 1u);
        st.counts.w = 1u;
        caustic = pc.trialCap == TRIAL_CAP_DROP ? vec3(0.0) : st.value.rgb * st.target.w;
    }
#ifndef LOOM_TEST_SMS_PREFIX_UNWEIGHTED  // the ablation the SMS tests must detect
    caustic *= st.beta.rgb;  // the camera path's specular prefix
#endif
    vec3 path = imageLoad(pathImage, ivec2(pixel)).rgb;
#if HAS_CAUSTIC
    imageStore(causticImage, ivec2(pixel), vec4(caustic, 1.0));
#endif
    imageStore(colorImage, ivec2(pixel), vec4(path + caustic, 1.0));
#if HAS_STATS
    // Newton iterations, solution found, trials, SMS estimate taken (1) or not (0).
    imageStore(statsImage, ivec2(pixel),
               vec4(float(st.counts.x), float(st.counts.z), float(st.counts.y),
                    status == SMS_NONE ? 0.0 : 1.0));
#endif
}
