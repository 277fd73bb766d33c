#version 460
// Test kernel: the primary-hit reconnection Jacobian |d u_lens_y / d u_lens_x| (Area ReSTIR,
// depth of field) against central finite differences of the lens sample, per pixel of a
// thin-lens scene, shifting to the pixel (+1, +1); the shift back must restore the lens sample
// with the inverse Jacobian (T^-1(T(x)) = x). Also the inverse concentric disk mapping.
#include "lib/restir/primary_shift.glsl"
#include "lib/restir/reservoir.glsl"
#include "lib/rng.glsl"
#include "lib/sampling.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
// J, J_fd (-1: skipped), concentric round-trip error, shift round-trip error (-1: no forward
// shift, 1e9: the shift back failed): max(|lens - lens back|, |J J_back - 1|).
layout(rgba32f) uniform writeonly image2D resultImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

bool lens_y(RestirSettings cfg, PathSample s, ivec2 a, ivec2 b, uint prim, out vec2 u, out float J) {
    CameraPose pose = scene_info.camera_open;
    PrimaryHit src = restir_domain_primary(cfg, s, PrimaryHit(vec4(0.0), uvec4(~0u)), a, pose);
    PathSample sy;
    PrimaryHit dst;
    u = vec2(0.0);
    J = 0.0;
    if (!primary_valid(src) || (prim != ~0u && src.hit.x != prim)) return false;
    if (!restir_primary_reconnect(s, src, vec2(a) + s.film_lens.xy, pose, false, vec2(b) + s.film_lens.xy,
                                  pose, false, pc.frameSize, sy, dst, J))
        return false;
    u = sy.film_lens.zw;
    return true;
}

bool near_kink(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    return abs(abs(o.x) - abs(o.y)) < 0.02;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    RestirSettings cfg;
    cfg.area = 1u;
    cfg.covered_max_chain = cfg.covered_depth = 0u;
    cfg.frame_size = pc.frameSize;
    Rng rng = rng_init(pixel, 0u, 11u);
    PathSample s = reservoir_empty().s;
    s.film_lens = vec4(rng_next2(rng), 0.2 + 0.6 * rng_next2(rng));
    ivec2 a = ivec2(pixel), b = a + ivec2(1, 1);
    vec4 result = vec4(0.0, -1.0, 0.0, -1.0);
    // Inverse concentric mapping round trip.
    vec2 u = rng_next2(rng);
    result.z = length(disk_concentric_inverse(sample_disk_concentric(u)) - u);
    vec2 u0;
    float J;
    CameraPose pose = scene_info.camera_open;
    PrimaryHit src = restir_domain_primary(cfg, s, PrimaryHit(vec4(0.0), uvec4(~0u)), a, pose);
    if (primary_valid(src) && lens_y(cfg, s, a, b, src.hit.x, u0, J)) {
        result.x = J;
        PathSample sy = s;
        sy.film_lens.zw = u0;
        vec2 u_back;
        float J_back;
        result.w = lens_y(cfg, sy, b, a, src.hit.x, u_back, J_back)
                       ? max(length(u_back - s.film_lens.zw), abs(J * J_back - 1.0))
                       : 1e9;
        const float eps = 1e-3;
        vec2 up[2], dn[2];
        float Jt;
        bool ok = true;
        for (int k = 0; k < 2; ++k) {
            vec2 e = k == 0 ? vec2(eps, 0.0) : vec2(0.0, eps);
            PathSample sp = s, sm = s;
            sp.film_lens.zw += e;
            sm.film_lens.zw -= e;
            ok = ok && lens_y(cfg, sp, a, b, src.hit.x, up[k], Jt) && lens_y(cfg, sm, a, b, src.hit.x, dn[k], Jt);
        }
        // Stay inside one octant of the concentric map (it is only piecewise smooth).
        ok = ok && !near_kink(s.film_lens.zw) && !near_kink(u0);
        if (ok) {
            vec2 c0 = (up[0] - dn[0]) / (2.0 * eps), c1 = (up[1] - dn[1]) / (2.0 * eps);
            result.y = abs(c0.x * c1.y - c0.y * c1.x);
        }
    }
    imageStore(resultImage, ivec2(pixel), result);
}
