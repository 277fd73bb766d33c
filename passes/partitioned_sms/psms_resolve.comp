#version 460
// PartitionedSMS, stage 3: the caustic estimate, the full image (path part + caustic), the
// per-pixel statistics and, for reuse (ManifoldReSTIRTemporal/Spatial), the sample as a
// reservoir: F = f T Le G and W = K / (P(C) p(x_n)), an unbiased contribution weight of the
// light point and solution (Hong et al. 2025 Sec. 5). Estimates that ran out of dispatches
// count as capped.
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
#if HAS_RESERVOIRS
layout(std430) writeonly buffer ReservoirsOut {
    ManifoldReservoirHeader header_out;
    ManifoldReservoir reservoirs_out[];
};
#endif

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint index = psms_pixel_index(pixel);
    PsmsPixel st = psms_pixels[index];
    uint status = st.hit.w;
    if (status != PSMS_NONE && status != PSMS_DONE) {
        // Out of dispatches: the trial cap, reached early.
        atomicAdd(psms_capped, 1u);
        st.counts.w = 1u;
        bool kept = status == PSMS_BERNOULLI && pc.trialCap == TRIAL_CAP_KEEP;
        st.x1.w = kept ? st.target.w / st.wo.w : 0.0;
    }
    vec3 caustic = status == PSMS_NONE ? vec3(0.0) : st.value.rgb * st.x1.w;
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
#if HAS_RESERVOIRS
    if (index == 0u)
        header_out.info = uvec4(MANIFOLD_RESERVOIR_MAGIC, pc.frameSize, min(pc.maxChain, 4u));
    // Every receiver gets a reservoir (confidence 1), with or without a sample: reuse can bring
    // one to it.
    PrimaryHit ph;
    ph.camera = vec4(st.camera.xyz, 1.0);
    ph.hit = uvec4(st.hit.xyz, 0u);  // ~0u: no receiver
    ManifoldReservoir r = manifold_reservoir_empty(ph);
    float pdf = st.light_y.w;
    if (status != PSMS_NONE && st.x1.w > 0.0 && pdf > 0.0 && luminance(st.value.rgb) > 0.0) {
        r.s.x1 = vec4(st.x1.xyz, 0.0);
        r.s.shapes = st.shapes;
        uint light = floatBitsToUint(st.light_n.w);
        r.s.light = manifold_light_coords(light, st.light_y.xyz);
        manifold_sample_set_offset_seed(r.s, psms_offset_seed(st));
        r.F.rgb = st.value.rgb * pdf;
        r.F.w = luminance(r.F.rgb);
        r.weight.x = st.x1.w / pdf;
    }
    reservoirs_out[index] = r;
#endif
}
