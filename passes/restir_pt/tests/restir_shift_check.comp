#version 460
// Test kernel: shifts each pixel's initial path sample back to its own primary hit (must give
// the stored integrand exactly: the generation and shift bookkeeping agree and the shift's
// invertibility checks accept the identity) and to the right-hand neighbour.
#include "lib/color.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/primary_shift.glsl"
#include "lib/restir/reservoir.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(rgba32f) uniform writeonly image2D checkImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    PathReservoir r = reservoirs_in[idx];
    vec4 out_value = vec4(0.0, 0.0, 0.0, -1.0);
    if (r.W > 0.0) {
        RestirSettings cfg = settings_in;
        CameraPose pose = scene_info.camera_open;
        // The own pixel, then the right-hand neighbour: one restir_shift call site (lavapipe
        // compiles every inlined shift separately).
        vec3 shifted_F[2];
        for (uint k = 0u; k < 2u; ++k) {
            ivec2 rp = ivec2(min(pixel.x + k, pc.frameSize.x - 1u), pixel.y);
            uint q = uint(rp.y) * pc.frameSize.x + uint(rp.x);
            shifted_F[k] = restir_shift(cfg, r.s, restir_domain_primary(cfg, r.s, primary_in[q], rp, pose));
        }
        vec3 self_F = shifted_F[0], other_F = shifted_F[1];
        // x: stored target, y: target after the self shift, z: neighbour target, w: rc index.
        out_value = vec4(r.target, luminance(self_F), luminance(other_F), float(path_rc_index(r.s)) + 16.0 * float(path_length(r.s)) + (path_last_nee(r.s) ? 256.0 : 0.0));
    }
    imageStore(checkImage, ivec2(pixel), out_value);
}
