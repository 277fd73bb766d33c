#version 460
// Reference unidirectional path tracer: BSDF sampling and next-event estimation combined by
// MIS (Veach 1997), Russian roulette, thin lens, motion blur over the shutter. The baseline
// every other estimator is tested against, so each strategy can be switched off.
#include "lib/camera.glsl"
#include "lib/integrator/nee.glsl"
#include "lib/rng.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
// Read-write: a frame's samples are split over dispatches that each add their share.
layout(rgba32f) uniform image2D colorImage;
#if HAS_ALBEDO
layout(rgba32f) uniform image2D albedoImage;
#endif
#if HAS_NORMAL
layout(rgba32f) uniform image2D normalImage;
#endif
#if HAS_DIRECT
layout(rgba32f) uniform image2D directImage;
#endif
#if HAS_INDIRECT
layout(rgba32f) uniform image2D indirectImage;
#endif
// Optional GBuffer inputs: the first sample's primary hit comes from the V-buffer instead of
// a trace, with the GBuffer's film and lens sample (same random stream positions).
#if HAS_VBUFFER
layout(rgba32ui) uniform readonly uimage2D vbufferImage;
#endif
#if HAS_SAMPLE
layout(rgba32f) uniform readonly image2D sampleImage;
#endif

// Rays traced this frame (closest + shadow), for Mrays/s, and the most BVH traversal steps one
// invocation ran (against lavapipe's loop limit, see bvh.glsl).
layout(std430) buffer RayCounter {
    uint ray_count;
    uint max_bvh_iterations;
};

// strategy (generated defines): STRATEGY_MIS = NEE + BSDF sampling with MIS, STRATEGY_BSDF =
// BSDF sampling only (emitters hit by chance), STRATEGY_NEE = light sampling only for non-delta
// vertices. Members are filled by name from PathTracer's declared parameters (KernelParams.h).

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint dispatchSamples;  // samples in this dispatch
    uint sampleBase;   // samples of this frame taken by earlier dispatches (0: the first)
    uint samplesPerPixel;  // samples of this frame over all its dispatches
    uint maxBounces;   // scattering events; 1 = direct lighting only
    uint rrDepth;      // Russian roulette starts after this many bounces
    uint strategy;
    uint misHeuristic;
    uint motionBlur;   // sample time over the shutter
    float clamp;       // 0 = off; biased firefly clamp for previews only
} pc;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    // Each dispatch of a frame draws from its own stream (the first one's is the unsplit stream).
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed + pc.sampleBase * 0x632BE5ABu);

    vec3 sum = vec3(0.0), sum_direct = vec3(0.0);
    vec3 first_albedo = vec3(0.0), first_normal = vec3(0.0);
    uint rays = 0u;
    for (uint s = 0u; s < pc.dispatchSamples; ++s) {
        // Camera ray: jittered film position, lens sample, shutter time.
        vec2 uv = (vec2(pixel) + rng_next2(rng)) / vec2(pc.frameSize);
        vec2 u_lens = rng_next2(rng);
        float shutter = pc.motionBlur != 0u ? rng_next(rng) : 0.0;
#if HAS_SAMPLE
        if (s == 0u && pc.sampleBase == 0u) {
            vec4 smp = imageLoad(sampleImage, ivec2(pixel));
            uv = (vec2(pixel) + smp.xy) / vec2(pc.frameSize);
            u_lens = smp.zw;
        }
#endif
        CameraFrame cam = camera_frame(scene_info.camera_open, scene_info.camera_close, shutter);
        vec3 o, d;
        camera_ray(cam, uv, u_lens, o, d);

        vec3 L = vec3(0.0), L_direct = vec3(0.0);
        vec3 beta = vec3(1.0);
        float prev_pdf = 0.0;     // solid-angle pdf of the BSDF sample that led here
        bool prev_delta = true;   // camera rays count as delta (no MIS at the first hit)
        vec3 prev_p = o;
        for (uint depth = 0u;; ++depth) {
            Hit hit;
            bool found;
#if HAS_VBUFFER
            if (s == 0u && pc.sampleBase == 0u && depth == 0u) {
                uvec4 v = imageLoad(vbufferImage, ivec2(pixel));
                hit.prim = v.x;
                hit.bary = uintBitsToFloat(v.yz);
                hit.t = 0.0;  // unused: shading works from prim and bary
                found = v.x != ~0u;
            } else
#endif
            {
                ++rays;
                found = trace_closest(o, d, 0.0, 1e30, BVH_MASK_ALL, hit);
            }
            ShadingPoint sh;
            if (found) sh = shading_point(hit);
            // Emission hit by BSDF sampling (or seen directly), or the environment on a miss,
            // MIS-weighted against light sampling.
            vec3 Le = emitter_hit_radiance(d, found, sh);
            if (any(greaterThan(Le, vec3(0.0)))) {
                float w = 1.0;
                if (!prev_delta && pc.strategy == STRATEGY_MIS)
                    w = mis_weight(prev_pdf, emitter_hit_light_pdf(prev_p, d, found, hit.prim, sh),
                                   pc.misHeuristic);
                else if (!prev_delta && pc.strategy == STRATEGY_NEE)
                    w = 0.0;
                vec3 c = beta * Le * w;
                L += c;
                if (depth <= 1u) L_direct += c;
            }
            if (!found) break;
            if (depth == 0u) {
                first_albedo += sh.mat.diffuse.rgb;
                first_normal += sh.n;
            }
            if (depth >= pc.maxBounces) break;

            vec3 wo = shading_to_local(sh, -d);
            uint flags = bsdf_flags(sh.mat);
            bool has_smooth = (flags & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u;

            // Next-event estimation.
            vec3 u_light = vec3(rng_next2(rng), rng_next(rng));
            if (has_smooth && pc.strategy != STRATEGY_BSDF) {
                NeeSample nee = nee_sample(sh, wo, u_light, pc.strategy == STRATEGY_MIS, pc.misHeuristic);
                if (nee.valid) {
                    ++rays;
                    if (!trace_any(nee.ray.o, nee.ray.d, 0.0, nee.ray.tmax, BVH_MASK_ALL)) {
                        vec3 c = beta * nee.value;
                        L += c;
                        if (depth == 0u) L_direct += c;
                    }
                }
            }

            // BSDF sampling.
            vec3 u_bsdf = vec3(rng_next(rng), rng_next2(rng));
            BsdfSample bs = bsdf_sample(sh.mat, wo, u_bsdf);
            if (!bsdf_sample_valid(bs)) break;
            beta *= bsdf_sample_weight(bs);
            prev_delta = (bs.flags & BSDF_DELTA) != 0u;
            prev_pdf = bs.pdf;
            prev_p = sh.sp.p;
            d = shading_to_world(sh, bs.wi);
            o = offset_ray_origin(sh.sp.p, sh.sp.ng, d);

            // Russian roulette on the throughput (unbiased: survivors are reweighted).
            if (depth + 1u >= pc.rrDepth) {
                float q = min(max(beta.r, max(beta.g, beta.b)), 0.95);
                if (rng_next(rng) >= q) break;
                beta /= q;
            }
            if (all(equal(beta, vec3(0.0)))) break;
        }
        if (pc.clamp > 0.0) L = min(L, vec3(pc.clamp));
        sum += L;
        sum_direct += L_direct;
    }
    atomicAdd(ray_count, rays);
    atomicMax(max_bvh_iterations, bvh_iterations);
    // This dispatch's share of the frame's mean, added to the earlier dispatches'.
    float inv = 1.0 / float(pc.samplesPerPixel);
    bool first = pc.sampleBase == 0u;
    ivec2 ip = ivec2(pixel);
    vec4 zero = vec4(0.0);
    imageStore(colorImage, ip, (first ? zero : imageLoad(colorImage, ip)) + vec4(sum * inv, first ? 1.0 : 0.0));
#if HAS_ALBEDO
    imageStore(albedoImage, ip, (first ? zero : imageLoad(albedoImage, ip)) + vec4(first_albedo * inv, first ? 1.0 : 0.0));
#endif
#if HAS_NORMAL
    imageStore(normalImage, ip, (first ? zero : imageLoad(normalImage, ip)) + vec4(first_normal * inv, first ? 1.0 : 0.0));
#endif
#if HAS_DIRECT
    imageStore(directImage, ip, (first ? zero : imageLoad(directImage, ip)) + vec4(sum_direct * inv, first ? 1.0 : 0.0));
#endif
#if HAS_INDIRECT
    imageStore(indirectImage, ip, (first ? zero : imageLoad(indirectImage, ip)) + vec4((sum - sum_direct) * inv, first ? 1.0 : 0.0));
#endif
}
