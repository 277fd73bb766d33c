// What PathTracer's two schedules share (path_tracer.comp, one invocation per pixel runs whole
// paths; path_tracer_wavefront.comp, paths advanced a vertex per dispatch): bindings,
// parameters, the camera sample and the per-pixel sums. Both take the same random numbers in
// the same order, so they render the same image (test_path_tracer.cpp checks it).
#ifndef LOOM_PATH_TRACER_COMMON_GLSL
#define LOOM_PATH_TRACER_COMMON_GLSL

#include "lib/camera.glsl"
#include "lib/integrator/path.glsl"
#include "lib/rng.glsl"

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
    uint dispatchSamples;  // samples in this chunk of the frame's samples
    uint sampleBase;       // samples of this frame taken by earlier chunks (0: the first)
    uint samplesPerPixel;  // samples of this frame over all its chunks
    uint maxBounces;       // scattering events; 1 = direct lighting only
    uint rrDepth;          // Russian roulette starts after this many bounces
    uint strategy;
    uint misHeuristic;
    uint motionBlur;       // sample time over the shutter
    float clamp;           // 0 = off; biased firefly clamp for previews only
#ifdef PT_WAVEFRONT
    uint sampleIndex;      // the sample of the chunk this wave traces (0 .. dispatchSamples - 1)
    uint bounceRound;      // the bounce dispatch (0: primary hits)
    uint finishPaths;      // 1: this bounce dispatch runs its paths to their end
#endif
} pc;

// Each chunk of a frame's samples draws from its own stream (the first one's is the unsplit
// stream).
Rng pt_rng(uvec2 pixel) {
    return rng_init(pixel, pc.frameIndex, pc.seed + pc.sampleBase * 0x632BE5ABu);
}

PathSettings pt_path_settings() {
    PathSettings ps;
    ps.max_bounces = pc.maxBounces;
    ps.rr_depth = pc.rrDepth;
    ps.mis_heuristic = pc.misHeuristic;
    ps.nee = pc.strategy != STRATEGY_BSDF;
    ps.mis = pc.strategy == STRATEGY_MIS;
    ps.covered_max_chain = 0u;
    ps.covered_depth = 0u;
    return ps;
}

// Camera ray of sample s of the chunk: jittered film position, lens sample, shutter time (set
// for the scene too, so that moving shapes are where they are at that time). given: the first
// hit is first (found: first_found), read from the V-buffer instead of traced. Returns the
// shutter time.
float pt_camera_sample(uvec2 pixel, uint s, inout Rng rng, out vec3 o, out vec3 d,
                       out bool given, out Hit first, out bool first_found) {
#ifdef RNG_SOBOL
    // sampler = sobol: sample s of this chunk is the pixel's sample number frame * spp + base
    // + s of its padded Sobol sequence (lib/rng.glsl), its draws dimension by dimension.
    rng = rng_sample_init(pixel, pc.frameIndex * pc.samplesPerPixel + pc.sampleBase + s, pc.seed);
#endif
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
    scene_set_time(shutter);
    camera_ray(cam, uv, u_lens, o, d);

    first.t = 0.0;
    first.prim = ~0u;
    first.bary = vec2(0.0);
    first_found = false;
    given = false;
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
    return shutter;
}

// A pixel's sums over the samples of a chunk.
struct PtPixelSums {
    vec3 color, direct, albedo, normal;
};

PtPixelSums pt_sums_none() {
    PtPixelSums s;
    s.color = vec3(0.0);
    s.direct = vec3(0.0);
    s.albedo = vec3(0.0);
    s.normal = vec3(0.0);
    return s;
}

void pt_sums_add(inout PtPixelSums s, PathRadiance pr) {
    vec3 L = pr.L;
    if (pc.clamp > 0.0) L = min(L, vec3(pc.clamp));
    s.color += L;
    s.direct += pr.L_direct;
    s.albedo += pr.albedo;
    s.normal += pr.normal;
}

// The chunk's share of the frame's mean, added to the earlier chunks'.
void pt_store(uvec2 pixel, PtPixelSums s) {
    float inv = 1.0 / float(pc.samplesPerPixel);
    bool first = pc.sampleBase == 0u;
    ivec2 ip = ivec2(pixel);
    vec4 zero = vec4(0.0);
    imageStore(colorImage, ip,
               (first ? zero : imageLoad(colorImage, ip)) + vec4(s.color * inv, first ? 1.0 : 0.0));
#if HAS_ALBEDO
    imageStore(albedoImage, ip,
               (first ? zero : imageLoad(albedoImage, ip)) + vec4(s.albedo * inv, first ? 1.0 : 0.0));
#endif
#if HAS_NORMAL
    imageStore(normalImage, ip,
               (first ? zero : imageLoad(normalImage, ip)) + vec4(s.normal * inv, first ? 1.0 : 0.0));
#endif
#if HAS_DIRECT
    imageStore(directImage, ip,
               (first ? zero : imageLoad(directImage, ip)) + vec4(s.direct * inv, first ? 1.0 : 0.0));
#endif
#if HAS_INDIRECT
    imageStore(indirectImage, ip, (first ? zero : imageLoad(indirectImage, ip)) +
                                      vec4((s.color - s.direct) * inv, first ? 1.0 : 0.0));
#endif
}

#endif
