#version 460
// Test kernel (tests/gpu/test_manifold.cpp): half-vector constraint and its directional
// derivative. Input rows: 0 w_i, 1 w_o, 2 n (w = eta), 3 s (w = 1 for reflection), 4 t,
// 5 dw_i, 6 dw_o, 7 ds, 8 dt. Output rows: 0 C, 1 dC.
#include "lib/manifold/constraints.glsl"

layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

vec4 row(int x, int y) { return imageLoad(inputImage, ivec2(x, y)); }

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= int(pc.frameSize.x)) return;
    vec3 wi = row(x, 0).xyz, wo = row(x, 1).xyz, s = row(x, 3).xyz, t = row(x, 4).xyz;
    vec4 n4 = row(x, 2);
    bool reflection = row(x, 3).w != 0.0;
    vec2 c = half_vector_constraint(wi, wo, n4.xyz, s, t, n4.w, reflection, vec2(0.0));
    vec2 dc = half_vector_constraint_derivative(wi, wo, n4.xyz, s, t, n4.w, reflection,
                                                row(x, 5).xyz, row(x, 6).xyz, row(x, 7).xyz,
                                                row(x, 8).xyz);
    imageStore(outputImage, ivec2(x, 0), vec4(c, 0.0, 0.0));
    imageStore(outputImage, ivec2(x, 1), vec4(dc, 0.0, 0.0));
}
