// Pinhole and thin-lens cameras (Mitsuba conventions: camera looks down +z of its frame, +x is
// left, +y up), with the camera moving linearly over the shutter for motion blur.
#ifndef LOOM_CAMERA_GLSL
#define LOOM_CAMERA_GLSL

#include "lib/sampling.glsl"

// One camera pose; SceneGpu uploads the pose at shutter open and at shutter close, plus the
// previous frame's (for motion vectors and temporal reuse).
struct CameraPose {
    vec4 origin;        // xyz, w = tan(fov_x / 2)
    vec4 target;        // xyz, w = tan(fov_y / 2)
    vec4 up;            // xyz, w = aperture radius (0 = pinhole)
    vec4 lens;          // x = focus distance, y = shutter length (frames), z = type
};

// LOOM_SCENE_THIN_LENS = 0 (set by the Renderer when no camera pose of the frame has an
// aperture) compiles every pose as a pinhole: the lens code is then dead, which matters on
// llvmpipe, where untaken branches still run masked.
#ifndef LOOM_SCENE_THIN_LENS
#define LOOM_SCENE_THIN_LENS 1
#endif

// Aperture radius of a pose (0: pinhole).
float camera_aperture(CameraPose p) { return LOOM_SCENE_THIN_LENS != 0 ? p.up.w : 0.0; }

struct CameraFrame {
    vec3 origin;
    vec3 right_axis;    // camera +x (points left in image space, Mitsuba)
    vec3 up_axis;
    vec3 forward;
    vec2 tan_half_fov;
    float aperture;
    float focus_distance;
};

CameraFrame camera_frame(CameraPose a, CameraPose b, float s) {
    CameraFrame c;
    c.origin = mix(a.origin.xyz, b.origin.xyz, s);
    vec3 target = mix(a.target.xyz, b.target.xyz, s);
    vec3 up = mix(a.up.xyz, b.up.xyz, s);
    c.forward = normalize(target - c.origin);
    c.right_axis = normalize(cross(up, c.forward));  // Mitsuba lookat: left = up x dir
    c.up_axis = cross(c.forward, c.right_axis);
    c.tan_half_fov = vec2(mix(a.origin.w, b.origin.w, s), mix(a.target.w, b.target.w, s));
    c.aperture = camera_aperture(a);
    c.focus_distance = a.lens.x;
    return c;
}

// The pose a fraction s of the way from a to b: camera_frame(camera_pose_at(a, b, s), ., 0)
// equals camera_frame(a, b, s) (lens from a).
CameraPose camera_pose_at(CameraPose a, CameraPose b, float s) {
    CameraPose p = a;
    p.origin = mix(a.origin, b.origin, s);
    p.target = mix(a.target, b.target, s);
    p.up.xyz = mix(a.up.xyz, b.up.xyz, s);
    return p;
}

// Primary ray through film position uv in [0,1]^2 (top-left origin) with lens sample u_lens.
void camera_ray(CameraFrame c, vec2 uv, vec2 u_lens, out vec3 origin, out vec3 dir) {
    vec3 d_cam = vec3((1.0 - 2.0 * uv.x) * c.tan_half_fov.x, (1.0 - 2.0 * uv.y) * c.tan_half_fov.y, 1.0);
    // The pinhole ray is computed the same way whether the lens code below is compiled in or
    // not (LOOM_SCENE_THIN_LENS), so both compile to the same floating-point operations.
    origin = c.origin;
    dir = normalize(d_cam.x * c.right_axis + d_cam.y * c.up_axis + c.forward);
    if (c.aperture > 0.0) {
        // Thin lens: all rays through the lens point converge on the focal plane z = focus.
        vec3 p_focus = d_cam * c.focus_distance;
        vec3 o_cam = vec3(c.aperture * sample_disk_concentric(u_lens), 0.0);
        d_cam = p_focus - o_cam;
        origin = c.origin + o_cam.x * c.right_axis + o_cam.y * c.up_axis;
        dir = normalize(d_cam.x * c.right_axis + d_cam.y * c.up_axis + d_cam.z * c.forward);
    }
}

// Thin-lens point on the focal plane seen through film position film_uv in [0,1]^2 (the point
// every lens sample's ray through film_uv passes, camera_ray).
vec3 camera_focal_point(CameraFrame cam, vec2 film_uv) {
    vec3 d = vec3((1.0 - 2.0 * film_uv.x) * cam.tan_half_fov.x,
                  (1.0 - 2.0 * film_uv.y) * cam.tan_half_fov.y, 1.0) * cam.focus_distance;
    return cam.origin + d.x * cam.right_axis + d.y * cam.up_axis + d.z * cam.forward;
}

// Film position (uv in [0,1]^2) of world point p, or false when behind the camera.
bool camera_project(CameraFrame c, vec3 p, out vec2 uv) {
    vec3 v = p - c.origin;
    float z = dot(v, c.forward);
    if (z <= 1e-6) return false;
    vec2 xy = vec2(dot(v, c.right_axis), dot(v, c.up_axis)) / z;
    uv = vec2(1.0 - xy.x / c.tan_half_fov.x, 1.0 - xy.y / c.tan_half_fov.y) * 0.5;
    return true;
}

#endif
