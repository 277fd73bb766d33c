#version 460
// PoissonReconstruct: the right-hand side of the normal equations, b = P^T W^2 [alpha f; g_x;
// g_y], with the weights scaled to mean 1 (the weight sums are in steps[weightSlot].rr):
//   b_i = s_i f_i - w_x(i) g_x(i) + w_x(i-1) g_x(i-1) - w_y(i) g_y(i) + w_y(i-up) g_y(i-up).
// The gradients are forward differences, g_x(p) = x(p + e_x) - x(p). With `initialize` the
// solution starts from the primal image.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D primalImage;
layout(rgba32f) uniform readonly image2D dxImage;
layout(rgba32f) uniform readonly image2D dyImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint weightSlot;
    uint initialize;
    uint xOffset;
    uint bOffset;
} pc;

vec4 rgb(vec4 v) { return vec4(v.rgb, 0.0); }

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    uint i = poisson_index(p, pc.frameSize);
    vec2 sums = steps[pc.weightSlot].rr.xy;
    float scale = sums.y / max(sums.x, 1e-30);  // 1 / mean weight
    vec4 wc = weight[i] * scale;
    vec4 f = rgb(imageLoad(primalImage, p));
    vec4 b = wc.x * f - wc.y * rgb(imageLoad(dxImage, p)) - wc.z * rgb(imageLoad(dyImage, p));
    if (p.x > 0) b += weight[i - 1u].y * scale * rgb(imageLoad(dxImage, p - ivec2(1, 0)));
    if (p.y > 0) b += weight[i - pc.frameSize.x].z * scale * rgb(imageLoad(dyImage, p - ivec2(0, 1)));
    vec[pc.bOffset + i] = b;
    if (pc.initialize != 0u) vec[pc.xOffset + i] = f;
}
