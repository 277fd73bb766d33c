// Test kernel body (passes/mnee_dr/tests/test_mnee_dr.cpp): one coplanarity walk per column
// against the loaded scene. Input rows: 0 P (w = 1: L is the direction towards a directional
// light), 1 L, 2 (max triangles, max bisections, tolerance, both directions). Output rows:
// 0 (status, triangles, bisections, prim), 1 (M, focusing factor D), 2 (barycentrics, sine
// between the scattered direction and the light's at M, how the other direction ended).
#include "lib/bvh.glsl"
#include "lib/manifold/coplanar_walk.glsl"

layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

vec4 row(int x, int y) { return imageLoad(inputImage, ivec2(x, y)); }

void main() {
    int x = int(gl_GlobalInvocationID.x);
    if (x >= int(pc.frameSize.x)) return;
    vec4 cfg = row(x, 2);
    CoplanarSettings cs;
    cs.max_triangles = uint(cfg.x);
    cs.max_bisections = uint(cfg.y);
    cs.bisection_tolerance = cfg.z;
    cs.both_directions = cfg.w != 0.0;
    CoplanarQuery q = coplanar_query(row(x, 0).xyz, row(x, 1).xyz, row(x, 0).w != 0.0);
    CoplanarResult res = coplanar_walk(q, cs);
    float D = 0.0, sine = -1.0;
    if (res.status == COPLANAR_SOLVED) {
        CoplanarTriangle tri = coplanar_triangle(res.prim, q);
        D = coplanar_focusing(tri, res.bary, q);
        sine = coplanar_condition(tri, res.bary, q, vec3(0.0), false).sine;
    }
    imageStore(outputImage, ivec2(x, 0),
               vec4(float(res.status), float(res.triangles), float(res.bisections), float(res.prim)));
    imageStore(outputImage, ivec2(x, 1), vec4(res.M, D));
    imageStore(outputImage, ivec2(x, 2), vec4(res.bary, sine, float(res.status_other)));
}
