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
    vec3 caustic = vec3(0.0);
    uvec3 counts = uvec3(0u);  // Newton iterations, trials, solutions over the receivers
    bool taken = false;
    for (uint i = 0u; i < uint(MANIFOLD_MAX_RECEIVERS); ++i) {
        SmsPixel st = sms_pixels[sms_slot(pixel, i)];
        uint status = st.hit.w;
        vec3 value = vec3(0.0);
        if (status == SMS_DONE || status == SMS_BIASED) {
            value = st.value.rgb;
        } else if (status == SMS_BERNOULLI || status == SMS_FIRST) {
            // Out of dispatches before the solution came back (or before the first walk
            // ended): the trial cap, reached early.
            atomicAdd(sms_capped, 1u);
            value = pc.trialCap == TRIAL_CAP_DROP ? vec3(0.0) : st.value.rgb * st.target.w;
        }
#ifndef LOOM_TEST_SMS_PREFIX_UNWEIGHTED  // the ablation the SMS tests must detect
        value *= st.beta.rgb;  // the camera path's prefix up to the receiver
#endif
#ifdef LOOM_TEST_LATER_RECEIVERS_LOST  // the ablation the SMS tests must detect
        if (i > 0u) value = vec3(0.0);
#endif
        caustic += value;
        counts += st.counts.xyz;
        taken = taken || status != SMS_NONE;
    }
    vec3 path = imageLoad(pathImage, ivec2(pixel)).rgb;
#if HAS_CAUSTIC
    imageStore(causticImage, ivec2(pixel), vec4(caustic, 1.0));
#endif
    imageStore(colorImage, ivec2(pixel), vec4(path + caustic, 1.0));
#if HAS_STATS
    // Newton iterations, solutions found, trials, SMS estimate taken (1) or not (0).
    imageStore(statsImage, ivec2(pixel),
               vec4(float(counts.x), float(counts.z), float(counts.y), taken ? 1.0 : 0.0));
#endif
}
