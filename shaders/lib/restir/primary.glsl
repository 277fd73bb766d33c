// The pixel's primary hit (PrimaryHit, reservoir.glsl) as ReSTIR PT stores it: tracing it for a
// film and lens sample, rebuilding its shading point, and the geometric similarity test that
// picks reuse techniques.
#ifndef LOOM_RESTIR_PRIMARY_GLSL
#define LOOM_RESTIR_PRIMARY_GLSL

#include "lib/camera.glsl"
#include "lib/lights.glsl"
#include "lib/restir/reservoir.glsl"
#include "lib/shading.glsl"

// The primary hit of the camera ray through film position (pixel + film_lens.xy) with lens
// sample film_lens.zw, seen by camera `pose` (Area ReSTIR samples carry these; the ray is traced
// again in every domain). A miss keeps the ray direction.
PrimaryHit restir_trace_primary(CameraPose pose, ivec2 pixel, vec4 film_lens, uvec2 frame_size) {
    CameraFrame cam = camera_frame(pose, pose, 0.0);
    vec3 o, d;
    camera_ray(cam, (vec2(pixel) + film_lens.xy) / vec2(frame_size), film_lens.zw, o, d);
    PrimaryHit ph;
    ph.camera = vec4(o, 1.0);
    Hit hit;
    ph.hit = trace_closest(o, d, 0.0, 1e30, BVH_MASK_ALL, hit)
                 ? uvec4(hit.prim, floatBitsToUint(hit.bary), 0u)
                 : uvec4(~0u, floatBitsToUint(d));
    return ph;
}

// The camera sample s sees in this frame (previous = false) or the previous one: the shutter-open
// pose, or with motion blur (restir_has_time) the pose at the sample's shutter time. With motion
// blur it also moves the shapes that move over the shutter to that time (scene_set_time), so
// every evaluation of a sample, which starts here, sees the scene at the sample's time.
CameraPose restir_sample_pose(RestirSettings cfg, PathSample s, bool previous) {
    CameraPose open = previous ? scene_info.camera_prev : scene_info.camera_open;
    if (!restir_has_time(cfg)) return open;
#ifndef LOOM_TEST_SHAPES_AT_SHUTTER_OPEN  // the ablation ReservoirSplat's test must detect
    scene_set_time(s.time);
#endif
    return camera_pose_at(open, previous ? scene_info.camera_prev_close : scene_info.camera_close,
                          s.time);
}

ShadingPoint restir_primary_shading(PrimaryHit ph) {
    Hit h;
    h.t = 0.0;
    h.prim = ph.hit.x;
    h.bary = uintBitsToFloat(ph.hit.yz);
    return shading_point(h);
}

// The emission seen at the primary hit (the environment on a miss): ReSTIR's path samples start
// after it, so every consumer of the reservoirs adds it apart.
vec3 restir_primary_emission(PrimaryHit ph) {
    if (!primary_valid(ph)) return environment_radiance(uintBitsToFloat(ph.hit.yzw));
    ShadingPoint sh = restir_primary_shading(ph);
    if (!any(greaterThan(sh.emission, vec3(0.0)))) return vec3(0.0);
    return emitted_radiance(sh.sp.shape, sh.sp.ng, normalize(sh.sp.p - ph.camera.xyz));
}

// Geometric similarity of two primary hits (a technique-set choice, independent of samples, so
// any rule is unbiased): normals within normal_threshold (cosine) and camera distances within
// depth_threshold relative. a is this frame's; b_previous: b is the previous frame's.
bool restir_similar(PrimaryHit a, PrimaryHit b, bool b_previous, float normal_threshold,
                    float depth_threshold) {
    if (!primary_valid(a) || !primary_valid(b)) return false;
    SurfacePoint sa = surface_point(a.hit.x, uintBitsToFloat(a.hit.yz));
    scene_select_frame(b_previous);
    SurfacePoint sb = surface_point(b.hit.x, uintBitsToFloat(b.hit.yz));
    scene_select_frame(false);
    if (dot(sa.ns, sb.ns) < normal_threshold) return false;
    float da = length(sa.p - a.camera.xyz), db = length(sb.p - b.camera.xyz);
    return abs(da - db) <= depth_threshold * max(da, db);
}

#endif
