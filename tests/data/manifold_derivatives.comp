#version 460
// Test kernel (tests/gpu/test_manifold.cpp): the angle-difference constraint at positions and
// its directional derivative. Input rows: 0 x_prev, 1 x (w = eta), 2 x_next (w = 1 for
// reflection), 3 n, 4 dx_prev, 5 dx, 6 dn, 7 dx_next, 8 the direction the frame is built from.
// Output rows: 0 (C, valid), 1 dC.
#include "lib/manifold/constraints.glsl"

layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

vec4 row(int x, int y) { return imageLoad(inputImage, ivec2(x, y)); }

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= int(pc.frameSize.x)) return;
    vec3 xp = row(x, 0).xyz, xn = row(x, 2).xyz, n = row(x, 3).xyz;
    vec4 x4 = row(x, 1);
    bool reflection = row(x, 2).w != 0.0;
    mat3 frame = manifold_angle_frame(row(x, 8).xyz);
    bool valid;
    vec2 c = angle_difference_constraint_at(xp, x4.xyz, xn, n, x4.w, reflection, frame, valid);
    vec2 dc = angle_difference_constraint_derivative(xp, x4.xyz, xn, n, x4.w, reflection, frame,
                                                     row(x, 4).xyz, row(x, 5).xyz, row(x, 6).xyz,
                                                     row(x, 7).xyz);
    imageStore(outputImage, ivec2(x, 0), vec4(c, valid ? 1.0 : 0.0, 0.0));
    imageStore(outputImage, ivec2(x, 1), vec4(dc, 0.0, 0.0));
}
