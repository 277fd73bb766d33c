#version 460
// Test kernel (tests/gpu/test_surface_point.cpp): shading_point's normal-mapped normal at given
// hits, with what an independent evaluation needs. Input row 0 per column: (prim, bary.x,
// bary.y, 0). Output rows: 0 the shading normal; 1 (uv, 0, 0); 2 and 3 the tangent frame
// (t, b) of the interpolated normal before mapping; 4 the interpolated normal.
#include "lib/shading.glsl"

layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= int(pc.frameSize.x)) return;
    vec4 in0 = imageLoad(inputImage, ivec2(x, 0));
    Hit h;
    h.prim = uint(in0.x);
    h.bary = in0.yz;
    h.t = 0.0;
    ShadingPoint s = shading_point(h);
    vec3 t, b;
    shading_tangent_frame(s.sp.ns, s.sp.tangent, t, b);
    imageStore(outputImage, ivec2(x, 0), vec4(s.n, 0.0));
    imageStore(outputImage, ivec2(x, 1), vec4(s.sp.uv, 0.0, 0.0));
    imageStore(outputImage, ivec2(x, 2), vec4(t, 0.0));
    imageStore(outputImage, ivec2(x, 3), vec4(b, 0.0));
    imageStore(outputImage, ivec2(x, 4), vec4(s.sp.ns, 0.0));
}
