#version 460
// Reference unidirectional path tracer: BSDF sampling and next-event estimation combined by
// MIS (Veach 1997), Russian roulette, thin lens, motion blur over the shutter. The baseline
// every other estimator is tested against, so each strategy can be switched off.
#include "lib/camera.glsl"
#include "lib/integrator/path.glsl"
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
        scene_set_time(shutter);  // moving shapes too, at the path's time
        vec3 o, d;
        camera_ray(cam, uv, u_lens, o, d);

        Hit first;
        first.t = 0.0;
        first.prim = ~0u;
        first.bary = vec2(0.0);
        bool first_found = false;
        bool given = false;
#if HAS_VBUFFER
        if (s == 0u && pc.sampleBase == 0u) {
            uvec4 v = imageLoad(vbufferImage, ivec2(pixel));
            first.prim = v.x;
            first.bary = uintBitsToFloat(v.yz);
            first.t = 0.0;  // unused: shading works from prim and bary
            first_found = v.x != ~0u;
            given = true;
        }
#endif
        PathSettings ps;
        ps.max_bounces = pc.maxBounces;
        ps.rr_depth = pc.rrDepth;
        ps.mis_heuristic = pc.misHeuristic;
        ps.nee = pc.strategy != STRATEGY_BSDF;
        ps.mis = pc.strategy == STRATEGY_MIS;
        ps.covered_max_chain = 0u;
        ps.covered_depth = 0u;
        PathRadiance pr = path_trace(o, d, given, first, first_found, ps, rng);
        rays += pr.rays;
        vec3 L = pr.L, L_direct = pr.L_direct;
        first_albedo += pr.albedo;
        first_normal += pr.normal;
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
