#version 460
// Test kernel for the splat shift (lib/restir/splat.glsl), per pixel of a frame whose camera
// (and shapes) moved since the previous one: a random film and lens sample Y here, its x1, the
// reverse splat T^-1(Y) into the previous frame, and the forward splat of that previous sample
// back here. Checks: T(T^-1(Y)) = Y, J(T^-1 Y) J_rev(Y) = 1, J against central differences of
// the film map previous -> here (the previous sample's primary ray traced again at perturbed
// film positions), the projection matching camera_ray, and the MIS partition of unity
// m_canonical(Y) + m_splat(T^-1 Y) [+ m_backup] = 1 for random confidences and targets, without
// and with the backup technique.
#include "lib/bvh.glsl"
#include "lib/camera.glsl"
#include "lib/rng.glsl"
#include "lib/restir/splat.glsl"
#include "lib/shading.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
// x: |T(T^-1 Y) - Y| (pixels), y: |J J_rev - 1|, z: |J_fd / J - 1| (-1: not checked),
// w: |m_canonical + m_splat - 1|. All -1 where Y has no valid reverse splat.
layout(rgba32f) uniform writeonly image2D resultImage;
// x: J, y: |projection of x1 here - film position of Y| (pixels), z: triangle area ratio.
layout(rgba32f) uniform writeonly image2D detailImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
} pc;

// x1 seen through film position `film` (pixels) with lens sample u of the given frame's camera.
bool primary_hit(bool previous, vec2 film, vec2 u, out Hit hit) {
    CameraPose pose = previous ? scene_info.camera_prev : scene_info.camera_open;
    CameraFrame c = camera_frame(pose, pose, 0.0);
    vec3 o, d;
    camera_ray(c, film / vec2(pc.frameSize), u, o, d);
    scene_select_frame(previous);
    bool found = trace_closest(o, d, 0.0, 1e30, BVH_MASK_ALL, hit);
    scene_select_frame(false);
    return found;
}

// Forward splat of the previous-frame sample at film position `film`: where it lands here.
bool forward(vec2 film, vec2 u, uint prim, out vec2 film_here, out float J) {
    Hit h;
    film_here = vec2(0.0);
    J = 0.0;
    if (!primary_hit(true, film, u, h) || h.prim != prim) return false;
    scene_select_frame(true);
    SurfacePoint xp = surface_point(h.prim, h.bary);
    FilmProjection from, to;
    bool ok = splat_project(scene_info.camera_prev, u, xp.p, xp.ng, pc.frameSize, from);
    scene_select_frame(false);
    SurfacePoint xc = surface_point(h.prim, h.bary);
    ok = ok && splat_project(scene_info.camera_open, u, xc.p, xc.ng, pc.frameSize, to);
    film_here = to.film;
    J = splat_jacobian(from, xp.area, to, xc.area);
    return ok;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    Rng rng = rng_init(pixel, pc.frameIndex, 0x51A7u);
    vec2 u_film = vec2(rng_next(rng), rng_next(rng)), u_lens = vec2(rng_next(rng), rng_next(rng));
    vec2 film = vec2(pixel) + u_film;
    imageStore(resultImage, ivec2(pixel), vec4(-1.0));
    imageStore(detailImage, ivec2(pixel), vec4(-1.0));
    Hit h;
    if (!primary_hit(false, film, u_lens, h)) return;
    SurfacePoint xc = surface_point(h.prim, h.bary);
    FilmProjection here, prev;
    if (!splat_project(scene_info.camera_open, u_lens, xc.p, xc.ng, pc.frameSize, here)) return;
    scene_select_frame(true);
    SurfacePoint xp = surface_point(h.prim, h.bary);
    bool ok = splat_project(scene_info.camera_prev, u_lens, xp.p, xp.ng, pc.frameSize, prev) &&
              film_on_screen(prev.film, pc.frameSize);
    scene_select_frame(false);
    if (!ok) return;
    float J_rev = splat_jacobian(here, xc.area, prev, xp.area);
    vec2 film_back;
    float J;
    if (!forward(prev.film, u_lens, h.prim, film_back, J)) return;  // occluded in the previous frame

    // Central differences of the map previous film -> film here, away from triangle edges.
    float J_fd = -1.0;
    const float eps = 0.01;
    vec2 fx0, fx1, fy0, fy1;
    float j;
    if (forward(prev.film - vec2(eps, 0.0), u_lens, h.prim, fx0, j) &&
        forward(prev.film + vec2(eps, 0.0), u_lens, h.prim, fx1, j) &&
        forward(prev.film - vec2(0.0, eps), u_lens, h.prim, fy0, j) &&
        forward(prev.film + vec2(0.0, eps), u_lens, h.prim, fy1, j)) {
        vec2 dx = (fx1 - fx0) / (2.0 * eps), dy = (fy1 - fy0) / (2.0 * eps);
        J_fd = abs(dx.x * dy.y - dx.y * dy.x);
    }
    float c_cur = 1.0 + 19.0 * rng_next(rng), c_r = 1.0 + 19.0 * rng_next(rng);
    float t_cur = exp(4.0 * rng_next(rng) - 2.0), t_prev = exp(4.0 * rng_next(rng) - 2.0);
    float c_b = 1.0 + 19.0 * rng_next(rng), t_b = exp(4.0 * rng_next(rng) - 2.0);
    // Without a backup (scatter), and with one (scatter_backup: three techniques).
    float m2 = splat_mis_canonical(c_cur, t_cur, c_r, t_prev, J_rev, 0.0) +
               splat_mis_prior(c_r, t_prev, c_cur, t_cur, J, 0.0);
    float m3 = splat_mis_canonical(c_cur, t_cur, c_r, t_prev, J_rev, c_b * t_b) +
               splat_mis_prior(c_r, t_prev, c_cur, t_cur, J, c_b * t_b) +
               splat_mis_backup(c_b, t_b, c_cur, t_cur, c_r, t_prev, J_rev);
    float m_sum = 1.0 + max(abs(m2 - 1.0), abs(m3 - 1.0));
    imageStore(resultImage, ivec2(pixel),
               vec4(length(film_back - film), abs(J * J_rev - 1.0),
                    J_fd < 0.0 ? -1.0 : abs(J_fd / J - 1.0), abs(m_sum - 1.0)));
    imageStore(detailImage, ivec2(pixel), vec4(J, length(here.film - film), xc.area / xp.area, 0.0));
}
