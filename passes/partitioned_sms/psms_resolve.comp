#version 460
// PartitionedSMS, stage 3: the caustic estimate, the full image (path part + caustic) and the
// per-pixel statistics. Estimates that ran out of dispatches count as capped.
#include "passes/partitioned_sms/psms_common.glsl"

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
    PsmsPixel st = psms_pixels[psms_pixel_index(pixel)];
    uint status = st.hit.w;
    vec3 caustic = vec3(0.0);
    if (status == PSMS_DONE) {
        caustic = st.value.rgb;
    } else if (status != PSMS_NONE) {
        // Out of dispatches: the trial cap, reached early.
        atomicAdd(psms_capped, 1u);
        st.counts.w = 1u;
        bool kept = status == PSMS_BERNOULLI && pc.trialCap == TRIAL_CAP_KEEP;
        caustic = kept ? st.value.rgb * (st.target.w / st.wo.w) : vec3(0.0);
    }
    vec3 path = imageLoad(pathImage, ivec2(pixel)).rgb;
#if HAS_CAUSTIC
    imageStore(causticImage, ivec2(pixel), vec4(caustic, 1.0));
#endif
    imageStore(colorImage, ivec2(pixel), vec4(path + caustic, 1.0));
#if HAS_STATS
    // Newton iterations, solution found, walks, estimate taken (1) or not (0).
    imageStore(statsImage, ivec2(pixel),
               vec4(float(st.counts.x), float(st.counts.z), float(st.counts.y),
                    status == PSMS_NONE ? 0.0 : 1.0));
#endif
}
