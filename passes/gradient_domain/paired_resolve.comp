#version 460
// The images of gradient-domain ReSTIR PT (Wang et al. 2025): each gradient is the sum over the
// pair's sign reservoirs of g(Y) W (with positivization the + and - parts, Sec. 5.2), the primal
// Area ReSTIR's F(Y) W, both without the emission seen at the primary hit, which is written
// apart. Forward differences with the Neumann convention PoissonReconstruct expects: dx(p) =
// I(p + e_x) - I(p), 0 in the last column.
#include "passes/gradient_domain/paired_pixel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer PairsIn {
    PairSettings pair_settings_in;
    PairSlots pairs_in[];
};
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(rgba32f) uniform writeonly image2D primalImage;
layout(rgba32f) uniform writeonly image2D dxImage;
layout(rgba32f) uniform writeonly image2D dyImage;
layout(rgba32f) uniform writeonly image2D directImage;
#if HAS_COLOR
layout(rgba32f) uniform writeonly image2D colorImage;
#endif

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint ablation;  // ABLATION_NONE, ABLATION_FLIP_GRADIENT_SIGN
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    uint idx = uint(p.y) * pc.frameSize.x + uint(p.x);
    PairSlots slots = pairs_in[idx];
    vec3 grad[2] = vec3[2](vec3(0.0), vec3(0.0));
    for (uint slot = 0u; slot < 4u; ++slot) {
        PairReservoir r = slots.slot[slot];
        if (r.W > 0.0 && pair_inside(p, slot >> 1, pc.frameSize)) grad[slot >> 1] += r.g * r.W;
    }
    if (pc.ablation == ABLATION_FLIP_GRADIENT_SIGN) {
        grad[0] = -grad[0];
        grad[1] = -grad[1];
    }
    PathReservoir r = reservoirs_in[idx];
    vec3 primal = r.W > 0.0 ? r.F * r.W : vec3(0.0);
    vec3 direct = restir_primary_emission(primary_in[idx]);
    imageStore(primalImage, p, vec4(primal, 1.0));
    imageStore(dxImage, p, vec4(grad[0], 0.0));
    imageStore(dyImage, p, vec4(grad[1], 0.0));
    imageStore(directImage, p, vec4(direct, 1.0));
#if HAS_COLOR
    imageStore(colorImage, p, vec4(primal + direct, 1.0));
#endif
}
