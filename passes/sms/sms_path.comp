#version 460
// SpecularManifoldSampling, stage 1: the camera path by the reference path tracer without the
// paths SMS covers (manifold/coverage.glsl), and, at each of the path's receivers (among its
// first maxReceivers vertices with a smooth lobe, behind at most receiverDepth specular vertices
// since the one before), the light sample an SMS estimate connects to. The estimate takes the
// path's own prefix: the path part leaves out the covered paths behind exactly that prefix, and
// the prefix's throughput weighs the estimate. Stage 2 (sms_trials.comp) runs the estimate's
// walks.
#include "lib/camera.glsl"
#include "lib/integrator/path.glsl"
#include "lib/rng.glsl"
#include "passes/sms/sms_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D pathImage;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    // The path tracer's stream and sample order (PathTracer with one sample per frame).
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
    ps.covered_depth = pc.receiverDepth;
    Hit none;
    none.t = 0.0;
    none.prim = ~0u;
    none.bary = vec2(0.0);
    PathRadiance pr = path_trace(o, d, false, none, false, ps, rng);
    imageStore(pathImage, ivec2(pixel), vec4(pr.L, 1.0));

    for (uint i = 0u; i < uint(MANIFOLD_MAX_RECEIVERS); ++i) {
        SmsPixel st;
        st.hit = uvec4(~0u, 0u, 0u, SMS_NONE);
        st.wo = vec4(-d, 0.0);
        st.rng = uvec4(0u);
        st.light_y = vec4(0.0);
        st.light_n = vec4(0.0);
        st.target = vec4(0.0);
        st.value = vec4(0.0);
        st.counts = uvec4(0u);
        st.beta = vec4(0.0);
        if (i < pr.receivers) {
            // A stream of its own per receiver: the path part stays the path tracer's image.
            Rng srng = rng_init(pixel, pc.frameIndex, pc.seed ^ (0x5A17C0DEu + i * 0x9E3779B9u));
            ManifoldLight ml = manifold_sample_light(vec3(rng_next2(srng), rng_next(srng)));
            if (ml.valid) {
                Hit x0 = pr.receiver_hit[i];
                st.hit = uvec4(x0.prim, floatBitsToUint(x0.bary),
                               pc.estimator == ESTIMATOR_BIASED ? SMS_BIASED : SMS_FIRST);
                st.wo = vec4(pr.receiver_wo[i], 0.0);
                st.beta = vec4(pr.receiver_beta[i], 0.0);
                st.rng = srng.state;
                st.light_y = vec4(ml.y, ml.pdf);
                st.light_n = vec4(ml.n, uintBitsToFloat(ml.light));
                atomicAdd(sms_samples, 1u);
                work_list_append(0u, sms_slot(pixel, i));
            }
        }
        sms_pixels[sms_slot(pixel, i)] = st;
    }
    atomicAdd(sms_rays, pr.rays);
    atomicMax(sms_max_bvh_iterations, bvh_iterations);
}
