#version 460
// Test kernel (tests/gpu/test_manifold.cpp): evaluates lib/manifold/constraints.glsl on
// configurations the test built in double precision. Input rows: 0 w_i, 1 n (w = eta),
// 2 w_o (w = 1 for reflection), 3 (a, b) angle pairs. Output rows: 0 (angle-difference C,
// valid, |half-vector C|), 1 wrap(a - b).
#include "lib/manifold/constraints.glsl"

layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= int(pc.frameSize.x)) return;
    vec3 wi = imageLoad(inputImage, ivec2(x, 0)).xyz;
    vec4 n4 = imageLoad(inputImage, ivec2(x, 1));
    vec4 wo4 = imageLoad(inputImage, ivec2(x, 2));
    vec2 ab = imageLoad(inputImage, ivec2(x, 3)).xy;
    bool reflection = wo4.w != 0.0;
    bool valid;
    vec2 c = angle_difference_constraint(wi, wo4.xyz, n4.xyz, n4.w, reflection,
                                         manifold_angle_frame(wo4.xyz), valid);
    vec3 s, t;
    orthonormal_basis(n4.xyz, s, t);
    vec2 h = half_vector_constraint(wi, wo4.xyz, n4.xyz, s, t, n4.w, reflection, vec2(0.0));
    imageStore(outputImage, ivec2(x, 0), vec4(c, valid ? 1.0 : 0.0, length(h)));
    imageStore(outputImage, ivec2(x, 1), vec4(manifold_wrap_angle(ab.x - ab.y), 0.0, 0.0, 0.0));
}
