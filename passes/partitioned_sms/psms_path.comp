#version 460
// PartitionedSMS, stage 1: the camera path by the reference path tracer without the paths SMS
// covers (as SpecularManifoldSampling's first stage), and at a primary receiver the
// light-caster pair and light point of the caustic sample (Hong et al. 2025 Sec. 4.2): the
// pair from the block's prior list with probability alpha, else uniform over the scene's
// pairs; the probability of the pair enters the light point's pdf.
#include "lib/camera.glsl"
#include "lib/integrator/path.glsl"
#include "passes/partitioned_sms/psms_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D pathImage;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed);
    vec2 uv = (vec2(pixel) + rng_next2(rng)) / vec2(pc.frameSize);
    vec2 u_lens = rng_next2(rng);
    CameraFrame cam = camera_frame(scene_info.camera_open, scene_info.camera_close, 0.0);
    vec3 o, d;
    camera_ray(cam, uv, u_lens, o, d);

    PathSettings ps;
    ps.max_bounces = pc.maxBounces;
    ps.rr_depth = pc.rrDepth;
    ps.mis_heuristic = pc.misHeuristic;
    ps.nee = true;
    ps.mis = true;
    ps.covered_max_chain = pc.excludeCovered != 0u ? min(pc.maxChain, uint(MANIFOLD_MAX_VERTICES)) : 0u;
    ps.covered_depth = 0u;
    Hit none;
    none.t = 0.0;
    none.prim = ~0u;
    none.bary = vec2(0.0);
    PathRadiance pr = path_trace(o, d, false, none, false, ps, rng);
    imageStore(pathImage, ivec2(pixel), vec4(pr.L, 1.0));

    PsmsPixel st;
    st.hit = uvec4(~0u, 0u, 0u, PSMS_NONE);
    st.wo = vec4(-d, 0.0);
    st.rng = uvec4(0u);
    st.light_y = vec4(0.0);
    st.light_n = vec4(0.0);
    st.target = vec4(0.0);
    st.value = vec4(0.0);
    st.counts = uvec4(0u);
    st.pair = uvec4(0u, ~0u, 0u, 0u);
    st.x1 = vec4(0.0);
    st.shapes = uvec4(MANIFOLD_NO_SHAPE);
    st.camera = vec4(o, 1.0);
    if (pr.found) {
        ShadingPoint sh = shading_point(pr.first);
        if (manifold_receiver(sh.shape_flags, sh.mat)) {
            // The receiver, kept for reuse even when no light point comes of it.
            st.hit = uvec4(pr.first.prim, floatBitsToUint(pr.first.bary), PSMS_NONE);
            Rng srng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x5A17C0DEu);
            uint block = prior_block(pixel, pc.frameSize);
            uint listed = pc.prior != 0u ? prior_list_length(block) : 0u;
            float a = listed > 0u ? pc.alpha : 0.0;
            uint pairs = manifold_pair_count();
            float r = rng_next(srng);
            uint pair, slot = ~0u;
            if (r < a) {
                slot = prior_sorted_slot(block, min(uint(r / a * float(listed)), listed - 1u), listed);
                pair = prior_slot_pair(block, slot);
            } else {
                pair = min(uint((r - a) / (1.0 - a) * float(pairs)), pairs - 1u);
                slot = listed > 0u ? prior_find(block, pair, listed) : ~0u;
            }
            float pair_pdf = (slot != ~0u ? a / float(listed) : 0.0) + (1.0 - a) / float(pairs);
            ManifoldLight ml =
                manifold_sample_pair_light(pair, vec3(rng_next2(srng), rng_next(srng)), pair_pdf);
            if (ml.valid) {
                st.hit = uvec4(pr.first.prim, floatBitsToUint(pr.first.bary), PSMS_FIRST);
                st.light_y = vec4(ml.y, ml.pdf);
                st.light_n = vec4(ml.n, uintBitsToFloat(ml.light));
                st.pair = uvec4(pair, slot, 0u, 0u);
                if (slot != ~0u)
                    st.pair.z = partition_set_size(prior_slot_base(block, slot), pc.tiles);
                st.rng = srng.state;
                atomicAdd(psms_samples, 1u);
                work_list_append(0u, psms_pixel_index(pixel));
            }
        }
    }
    psms_pixels[psms_pixel_index(pixel)] = st;
    atomicAdd(psms_rays, pr.rays);
    atomicMax(psms_max_bvh_iterations, bvh_iterations);
}
