#version 460
// ReSTIR PT final shading: emission seen at the primary hit plus the reservoir's estimate
// F(Y) W (Lin et al. 2022, Eq. 6).
#include "lib/lights.glsl"
#include "lib/restir/primary.glsl"
#include "lib/restir/reservoir.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(rgba32f) uniform writeonly image2D colorImage;

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint emission;  // add the primary hit's emission (else: only the resampled paths)
} pc;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    PrimaryHit ph = primary_in[idx];
    vec3 L = vec3(0.0);
    if (pc.emission != 0u) L += restir_primary_emission(ph);
    PathReservoir r = reservoirs_in[idx];
    if (r.W > 0.0) L += r.F * r.W;
    imageStore(colorImage, ivec2(pixel), vec4(L, 1.0));
}
