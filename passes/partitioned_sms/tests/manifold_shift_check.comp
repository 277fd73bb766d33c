#version 460
// Test kernel (test_manifold_restir.cpp): the manifold shift on PartitionedSMS's reservoirs.
// Per pixel with a sample x (else all -3):
//   x: |T_c->c(x).x1 - x.x1| (the shift to its own pixel; -1 when it fails)
//   y: |F(T_c->c(x)) - F(x)| / |F(x)|
//   z: |T_q->c(T_c->q(x)).x1 - x.x1| for the receiver q = c + (5, 2), both shifts with the walk
//      back (-1: T_c->q failed, -2: it succeeded and its inverse failed; -3: no receiver at q)
//   w: the same with the walk back off, -1 / -2 / -3 as for z
#include "lib/manifold/shift.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    ManifoldReservoirHeader header_in;
    ManifoldReservoir reservoirs_in[];
};
layout(rgba32f) uniform writeonly image2D outputImage;
layout(push_constant) uniform Params { uvec2 frameSize; } pc;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    ManifoldReservoir rc = reservoirs_in[pixel.y * pc.frameSize.x + pixel.x];
    vec4 out_value = vec4(-3.0);
    if (rc.weight.x > 0.0) {
        ManifoldShiftSettings ss;
        ss.ms.constraint = MANIFOLD_CONSTRAINT_ANGLE_DIFFERENCE;
        ss.ms.max_iterations = 5u;
        ss.ms.solver_threshold = 1e-5;
        ss.ms.min_segment = 1e-4;
        ss.ms.step_control = MANIFOLD_STEP_REPROJECTION;
        ss.ms.max_chain = 2u;
        ss.uniqueness_threshold = 1e-5;
        ss.geometric_clamp = 0.0;
        ss.bijective = true;
        // Job 0: the shift to its own pixel; jobs 1 and 3: c -> q with the walk back on and
        // off; jobs 2 and 4: back to c. One manifold_shift call site: lavapipe compiles every
        // inlined walk separately, and three call sites tripled this kernel's compile time.
        uvec2 q = pixel + uvec2(5u, 2u);
        ManifoldReservoir rq;
        bool has_q = all(lessThan(q, pc.frameSize));
        if (has_q) {
            rq = reservoirs_in[q.y * pc.frameSize.x + q.x];
            has_q = primary_valid(rq.receiver);
        }
        float r[2] = float[2](-3.0, -3.0);
        ManifoldSample forward = rc.s;
        for (uint job = 0u; job < (has_q ? 5u : 1u); ++job) {
            bool back = job != 0u && job % 2u == 0u;
            uint b = job == 0u ? 0u : (job - 1u) / 2u;
            if (back && r[b] != -2.0) continue;  // the forward shift failed
            ss.bijective = b == 0u;
            ManifoldSample t;
            vec3 F;
            bool ok = manifold_shift(back ? forward : rc.s, back ? rq.receiver : rc.receiver,
                                     false, (job == 0u || back) ? rc.receiver : rq.receiver,
                                     false, ss, t, F);
            if (job == 0u) {
                out_value.x = ok ? length(t.x1.xyz - rc.s.x1.xyz) : -1.0;
                if (ok) out_value.y = length(F - rc.F.rgb) / length(rc.F.rgb);
            } else if (!back) {
                r[b] = ok ? -2.0 : -1.0;
                forward = t;
            } else if (ok) {
                r[b] = length(t.x1.xyz - rc.s.x1.xyz);
            }
        }
        out_value.z = r[0];
        out_value.w = r[1];
    }
    imageStore(outputImage, ivec2(pixel), out_value);
}
