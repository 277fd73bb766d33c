// What the two MNEEDimReduction kernels share: their parameters (filled by name from the
// pass's declaration) and the frame's counters. Layouts mirrored by MNEEDimReductionPass.cpp.
#ifndef LOOM_PASSES_MNEE_DR_COMMON_GLSL
#define LOOM_PASSES_MNEE_DR_COMMON_GLSL

#include "lib/camera.glsl"
#include "lib/rng.glsl"
#include "lib/scene.glsl"

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint maxTriangles;
    uint maxBisections;
    float bisectionTolerance;
    uint bothDirections;
    uint receiverDepth;
    uint maxBounces;
    uint rrDepth;
    uint misHeuristic;
    uint excludeCovered;
} pc;

// Frame totals: walks, one count per COPLANAR_* status, triangles entered, bisection steps,
// the largest BVH step count of an invocation, rays.
layout(std430) buffer MneeDrCounters { uint mnee_dr_counters[16]; };
const uint COUNTER_WALKS = 0u, COUNTER_STATUS = 1u, COUNTER_TRIANGLES = 9u,
           COUNTER_BISECTIONS = 10u, COUNTER_MAX_STEPS = 11u, COUNTER_RAYS = 12u;

// The stream a pixel's camera ray comes from, the same in both kernels (PathTracer's stream
// and sample order with one sample per frame): the caustic kernel retraces the ray the path
// kernel traced.
Rng mnee_dr_camera_ray(uvec2 pixel, out vec3 o, out vec3 d) {
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed);
    vec2 uv = (vec2(pixel) + rng_next2(rng)) / vec2(pc.frameSize);
    vec2 u_lens = rng_next2(rng);
    CameraFrame cam = camera_frame(scene_info.camera_open, scene_info.camera_close, 0.0);
    camera_ray(cam, uv, u_lens, o, d);
    return rng;
}

#endif
