#version 460
// ReSTIR PT initial candidates (Lin et al. 2022, Sec. 5): per pixel, `candidates` paths from
// the GBuffer's primary hit, every NEE sample and emitter hit streamed into one path reservoir
// by RIS with the luminance target. Also writes the pixel's primary hit (the GBuffer's), which
// later passes use to pick reuse techniques (neighbour similarity) and to shade emission.
// ReSTIR PT: candidates start at that hit and record its film and lens sample. Area ReSTIR
// (Zhang et al. 2024): film and lens samples are part of the path and shifts replay them at the
// destination pixel; each candidate draws its own and traces its own primary ray, so that the
// technique choices, made from the GBuffer's hit, are independent of the samples they weight
// (starting candidates at the GBuffer's sample darkened Area ReSTIR by ~6% along edges under
// camera motion).
#include "lib/camera.glsl"
#include "lib/restir/generation.glsl"
#include "lib/restir/primary.glsl"
#include "lib/restir/reservoir.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32ui) uniform readonly uimage2D vbufferImage;
layout(rgba32f) uniform readonly image2D sampleImage;  // subpixel xy, lens uv (GBuffer)
layout(std430) writeonly buffer ReservoirsOut {
    RestirSettings settings_out;
    PathReservoir reservoirs_out[];
};
layout(std430) writeonly buffer PrimaryOut { PrimaryHit primary_out[]; };
layout(std430) buffer RayCounter {
    uint ray_count;
    uint max_bvh_iterations;  // most traversal steps of one invocation (bvh.glsl limit)
};

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint candidates;
    uint maxBounces;
    uint shift;
    float roughnessThreshold;
    float distanceThreshold;
    uint misHeuristic;
    uint reuse;  // REUSE_PATH, REUSE_AREA
    uint rrDepth;
    uint motionBlur;
    uint coveredMaxChain;  // 0: every path; else leave out what a caustic estimator covers
    uint coveredDepth;
} pc;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    RestirSettings cfg;
    cfg.max_bounces = pc.maxBounces;
    cfg.shift = pc.shift;
    cfg.rough_threshold = pc.roughnessThreshold;
    cfg.dist_threshold = pc.distanceThreshold;
    cfg.frame_size = pc.frameSize;
    cfg.mis_heuristic = pc.misHeuristic;
    cfg.area = pc.reuse == REUSE_AREA ? RESTIR_AREA | (pc.motionBlur != 0u ? RESTIR_AREA_TIME : 0u) : 0u;
    cfg.covered_max_chain = pc.coveredMaxChain;
    cfg.covered_depth = pc.coveredDepth;
    if (idx == 0u) settings_out = cfg;

    // The camera vertex of the GBuffer's primary ray (same film and lens sample, shutter open).
    vec4 smp = imageLoad(sampleImage, ivec2(pixel));
    CameraFrame cam = camera_frame(scene_info.camera_open, scene_info.camera_close, 0.0);
    vec3 o, d;
    camera_ray(cam, (vec2(pixel) + smp.xy) / vec2(pc.frameSize), smp.zw, o, d);
    uvec4 v = imageLoad(vbufferImage, ivec2(pixel));
    PrimaryHit ph;
    ph.camera = vec4(o, 1.0);
    // A miss keeps the ray direction so shading can look up the environment.
    ph.hit = v.x == ~0u ? uvec4(~0u, floatBitsToUint(d)) : uvec4(v.xyz, 0u);
    primary_out[idx] = ph;

    PathReservoir r = reservoir_empty();
    Rng rng_sel = rng_init(pixel, pc.frameIndex, pc.seed ^ 0xA511E9B3u);
    Rng rng_film = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x3C6EF372u);
    uint rays = 0u;
    if (primary_valid(ph) || pc.reuse == REUSE_AREA) {
        float inv = 1.0 / float(pc.candidates);
        for (uint c = 0u; c < pc.candidates; ++c) {
            uvec4 seed = rng_init(pixel, pc.frameIndex, pc.seed ^ (0x9E3779B1u * (c + 1u))).state;
            vec4 film_lens = smp;
            PrimaryHit cph = ph;
            PathSample cs;
            cs.time = 0.0;
            if (pc.reuse == REUSE_AREA) {
                film_lens = vec4(rng_next2(rng_film), rng_next2(rng_film));
                // Motion blur: a shutter time per candidate (PathTracer's uniform shutter fraction).
                if (restir_has_time(cfg)) cs.time = rng_next(rng_film);
                cph = restir_trace_primary(restir_sample_pose(cfg, cs, false), ivec2(pixel), film_lens,
                                           pc.frameSize);
                ++rays;
            }
            rays += restir_generate(cfg, cph, seed, film_lens, cs.time, inv, pc.rrDepth, r, rng_sel);
        }
        r.M = float(pc.candidates);
    }
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
    atomicAdd(ray_count, rays);
    atomicMax(max_bvh_iterations, bvh_iterations);
}
