#version 460
// Gradients after ReSTIR, the baseline of gradient-domain ReSTIR PT (Wang et al. 2025): each
// pixel's final reservoir sample Y (Area ReSTIR's or ReSTIR PT's) with its unbiased contribution
// weight W is shifted to the four neighbouring pixels by the hybrid shift, giving the one-sided
// estimate m (F'(T Y) - F(Y)) W of I(neighbour) - I(here). The pair's weights are the balance
// heuristic on the target functions, m = p(Y) / (p(Y) + p'(T Y)) with p = luminance(F): W stands
// in for the resampled density nobody knows, and any weights that sum to 1 over a pair's two
// techniques (this pixel's sample shifted there, the neighbour's shifted here; the shifts' mixed
// measure has Jacobian 1) keep the two-sided sum unbiased; a failed shift leaves m = 1.
// The primal is the reservoir's own estimate F W; the emission at the primary hit is written
// apart (as ReSTIRPTShade adds it). gpt_resolve.comp assembles the images.
#include "lib/color.glsl"
#include "lib/lights.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/primary_shift.glsl"
#include "passes/gradient_domain/gradient_pixels.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(std430) writeonly buffer GradientPixels { GradientPixel gradient_pixels[]; };

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint ablation;  // ABLATION_*: biased variants for the tests
} pc;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    RestirSettings cfg = settings_in;
    GradientPixel o;
    o.primal = vec4(0.0);
    for (uint d = 0u; d < 4u; ++d) {
        o.neighbour[d] = vec4(0.0);
        o.gradient[d] = vec4(0.0);
    }
    PrimaryHit ph = primary_in[idx];
    o.direct = vec4(restir_primary_emission(ph), 0.0);

    PathReservoir r = reservoirs_in[idx];
    if (r.W > 0.0) {
        o.primal = vec4(r.F * r.W, 0.0);
        CameraPose pose = restir_sample_pose(cfg, r.s, false);
        float sign = pc.ablation == ABLATION_FLIP_GRADIENT_SIGN ? -1.0 : 1.0;
        for (uint d = 0u; d < 4u; ++d) {
            ivec2 q = ivec2(pixel) + kGradientOffsets[d];
            if (!gradient_inside(q, pc.frameSize)) continue;
            uint qi = uint(q.y) * pc.frameSize.x + uint(q.x);
            vec3 F_offset = restir_shift(cfg, r.s, restir_domain_primary(cfg, r.s, primary_in[qi], q, pose));
            float t = luminance(r.F), t_offset = luminance(F_offset);
            float m = t / (t + t_offset);
            o.gradient[d] = vec4(sign * m * (F_offset - r.F) * r.W, 0.0);
        }
    }
    gradient_pixels[idx] = o;
}
