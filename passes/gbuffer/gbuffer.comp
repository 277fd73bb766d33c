#version 460
// GBuffer (V-buffer + derived attributes) of the primary hits, with the film/lens/time sample
// that produced them, so later passes can re-trace or shift the exact primary ray.
#include "lib/camera.glsl"
#include "lib/rng.glsl"
#include "lib/shading.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32ui) uniform writeonly uimage2D vbufferImage;   // prim (~0 = miss), bary.xy bits, shape
layout(r32f) uniform writeonly image2D depthImage;           // view-space depth (0 = miss)
layout(rgba32f) uniform writeonly image2D normalImage;       // shading normal
layout(rgba32f) uniform writeonly image2D geoNormalImage;    // geometric normal
layout(rgba32f) uniform writeonly image2D positionImage;     // world position, w = 1 (0 = miss)
layout(rgba32f) uniform writeonly image2D albedoImage;
layout(r32f) uniform writeonly image2D roughnessImage;       // microfacet alpha (0 = smooth)
layout(rg32f) uniform writeonly image2D motionImage;         // previous film position - current, pixels
layout(rgba32f) uniform writeonly image2D sampleImage;       // subpixel xy, lens uv
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint jitter;
    uint motionBlur;
} pc;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    // Same stream layout as the path tracer's first sample: film, lens, shutter.
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed);
    vec2 sub = pc.jitter != 0u ? rng_next2(rng) : vec2(0.5);
    vec2 u_lens = rng_next2(rng);
    float shutter = pc.motionBlur != 0u ? rng_next(rng) : 0.0;
    CameraFrame cam = camera_frame(scene_info.camera_open, scene_info.camera_close, shutter);
    scene_set_time(shutter);  // moving shapes at the same time: the path tracer's first hit
    vec3 o, d;
    camera_ray(cam, (vec2(pixel) + sub) / vec2(pc.frameSize), u_lens, o, d);
    ivec2 ip = ivec2(pixel);
    imageStore(sampleImage, ip, vec4(sub, u_lens));

    Hit hit;
    if (!trace_closest(o, d, 0.0, 1e30, BVH_MASK_ALL, hit)) {
        imageStore(vbufferImage, ip, uvec4(~0u, 0u, 0u, ~0u));
        imageStore(depthImage, ip, vec4(0.0));
        imageStore(normalImage, ip, vec4(0.0));
        imageStore(geoNormalImage, ip, vec4(0.0));
        imageStore(positionImage, ip, vec4(0.0));
        imageStore(albedoImage, ip, vec4(0.0));
        imageStore(roughnessImage, ip, vec4(0.0));
        imageStore(motionImage, ip, vec4(0.0));
        return;
    }
    ShadingPoint sh = shading_point(hit);
    imageStore(vbufferImage, ip, uvec4(hit.prim, floatBitsToUint(hit.bary), sh.sp.shape));
    imageStore(depthImage, ip, vec4(dot(sh.sp.p - cam.origin, cam.forward)));
    imageStore(normalImage, ip, vec4(sh.n, 0.0));
    imageStore(geoNormalImage, ip, vec4(sh.sp.ng, 0.0));
    imageStore(positionImage, ip, vec4(sh.sp.p, 1.0));
    imageStore(albedoImage, ip, vec4(sh.mat.diffuse.rgb, 1.0));
    imageStore(roughnessImage, ip, vec4(material_alpha(sh.mat)));
    // Motion vector: where the hit point was on the previous frame's film (camera motion and
    // rigid shape motion). Both ends are pinhole projections of the point: under a thin lens the
    // sample's film position is off the point's projection by its defocus, and a motion vector
    // must not depend on the lens sample (Area ReSTIR picks its temporal partner with it, and a
    // technique choice that depends on the canonical sample biases the MIS). Pinhole: the same.
    vec2 uv_prev, uv_now;
    CameraFrame prev = camera_frame(scene_info.camera_prev, scene_info.camera_prev, 0.0);
    vec2 mv = vec2(0.0);
    if (camera_project(prev, previous_position(sh.sp.shape, sh.sp.p), uv_prev) &&
        camera_project(cam, sh.sp.p, uv_now))
        mv = (uv_prev - uv_now) * vec2(pc.frameSize);
    imageStore(motionImage, ip, vec4(mv, 0.0, 0.0));
}
