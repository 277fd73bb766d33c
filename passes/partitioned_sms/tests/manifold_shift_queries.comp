#version 460
// Test kernel (test_manifold_restir.cpp, ManifoldReuse.OneStepIsExactlyUnbiased...): manifold
// shifts of explicit caustic samples between explicit receivers. Query k occupies column
// k % width of the 6-row block k / width of the input image (the invocation at the block's
// first row runs it):
//   row 0: (ray origin to the source receiver, 0)   row 1: (its direction, bijective walk back)
//   row 2: (ray origin to the destination, 0)       row 3: (its direction, Newton iterations)
//   row 4: (the sample's first vertex x1: the source solution, or any seed point, light index)
//   row 5: (the light point's barycentrics on that light, caster shape of vertex 1, of vertex 2
//           or -1)
// Output, same block: row 0 (t.x1, 1 when the shift succeeded), row 1 (F = f T Le G at the
// destination, luminance(F)). With source = destination and the walk back off, a query is one
// solve from its seed: how the test enumerates a receiver's solutions.
#include "lib/manifold/shift.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D inputImage;
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

vec4 row(uvec2 p, uint r) { return imageLoad(inputImage, ivec2(p.x, p.y + r)); }

PrimaryHit trace_receiver(vec3 o, vec3 d) {
    PrimaryHit ph;
    ph.camera = vec4(o, 1.0);
    Hit hit;
    ph.hit = trace_closest(o, d, 0.0, 1e30, BVH_MASK_ALL, hit)
                 ? uvec4(hit.prim, floatBitsToUint(hit.bary), 0u)
                 : uvec4(~0u, floatBitsToUint(d));
    return ph;
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, pc.frameSize)) || p.y % 6u != 0u || p.y + 5u >= pc.frameSize.y)
        return;
    PrimaryHit from = trace_receiver(row(p, 0u).xyz, row(p, 1u).xyz);
    PrimaryHit to = trace_receiver(row(p, 2u).xyz, row(p, 3u).xyz);
    ManifoldShiftSettings ss;
    ss.ms.constraint = MANIFOLD_CONSTRAINT_ANGLE_DIFFERENCE;
    ss.ms.max_iterations = uint(row(p, 3u).w);
    ss.ms.solver_threshold = 1e-5;
    ss.ms.min_segment = 1e-4;
    ss.ms.step_control = MANIFOLD_STEP_REPROJECTION;
    ss.ms.max_chain = 2u;
    ss.uniqueness_threshold = 1e-5;
    ss.geometric_clamp = 0.0;
    ss.bijective = row(p, 1u).w > 0.5;
    ManifoldSample s;
    s.x1 = vec4(row(p, 4u).xyz, 0.0);
    vec4 r5 = row(p, 5u);
    s.shapes = uvec4(uint(r5.z), r5.w < 0.0 ? MANIFOLD_NO_SHAPE : uint(r5.w), MANIFOLD_NO_SHAPE,
                     MANIFOLD_NO_SHAPE);
    s.light = vec4(r5.xy, uintBitsToFloat(uint(row(p, 4u).w)), 0.0);
    ManifoldSample t;
    vec3 F;
    bool ok = primary_valid(from) && primary_valid(to) &&
              manifold_shift(s, from, false, to, false, ss, t, F);
    imageStore(outputImage, ivec2(p), vec4(t.x1.xyz, ok ? 1.0 : 0.0));
    imageStore(outputImage, ivec2(p.x, p.y + 1u), vec4(F, ok ? luminance(F) : 0.0));
}
