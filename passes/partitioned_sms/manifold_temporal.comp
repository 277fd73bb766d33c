#version 460
// ManifoldReSTIRTemporal (Hong et al. 2025 Sec. 5): the previous frame's reservoir at the
// receiver's reprojection (camera motion and rigid shape motion, as GBuffer's motion vectors)
// is shifted here by the manifold shift, and this frame's sample there (in the previous frame's
// geometry) for its MIS weight; the two are combined by the generalized balance heuristic with
// confidences (pairwise MIS of two techniques), the history's confidence capped at
// confidenceCap times the canonical one.
#include "lib/camera.glsl"
#include "passes/partitioned_sms/manifold_reuse.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer PrevReservoirs {
    ManifoldReservoirHeader header_prev;
    ManifoldReservoir reservoirs_prev[];
};

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint historyReset;  // the previous-frame reservoirs hold no frame yet (Renderer::reset)
    uint constraint;
    uint shiftIterations;
    float solverThreshold;
    float uniquenessThreshold;
    uint bijectivity;
    float geometricTermClamp;
    uint maxChain;
    float minSegment;
    float confidenceCap;
    float normalThreshold;
    float depthThreshold;
} pc;

// The previous frame's pixel of receiver ph: where its surface point was, seen by the previous
// frame's camera (a pinhole projection, as GBuffer's motion vectors).
bool manifold_previous_pixel(PrimaryHit ph, out ivec2 q) {
    SurfacePoint sp = surface_point(ph.hit.x, uintBitsToFloat(ph.hit.yz));
    CameraFrame prev = camera_frame(scene_info.camera_prev, scene_info.camera_prev, 0.0);
    vec2 uv;
    if (!camera_project(prev, previous_position(sp.shape, sp.p), uv)) return false;
    q = ivec2(floor(uv * vec2(pc.frameSize)));
    return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(pc.frameSize)));
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint index = pixel.y * pc.frameSize.x + pixel.x;
    if (index == 0u) header_out = header_in;
    ManifoldReservoir rc = reservoirs_in[index];
    if (!primary_valid(rc.receiver)) {
        manifold_reuse_finish(pixel, index, rc, 0u, 0u);
        return;
    }
    // History made under the same frame size and chain length only (the first frame, the frame
    // after a reset and the frame after a change have none).
    ManifoldReservoirHeader hp = header_prev;
    bool history = pc.historyReset == 0u && hp.info.x == MANIFOLD_RESERVOIR_MAGIC && all(equal(hp.info.yz, pc.frameSize)) &&
                   hp.info.w == header_in.info.w;
    ivec2 q;
    ManifoldReservoir rh;
    if (history) history = manifold_previous_pixel(rc.receiver, q);
    if (history) {
        rh = reservoirs_prev[uint(q.y) * pc.frameSize.x + uint(q.x)];
        history = restir_similar(rc.receiver, rh.receiver, true, pc.normalThreshold,
                                 pc.depthThreshold);
    }
    if (!history) {
        manifold_reuse_finish(pixel, index, rc, 0u, 0u);
        return;
    }
    ManifoldShiftSettings ss = manifold_reuse_settings(
        pc.constraint, pc.shiftIterations, pc.solverThreshold, pc.uniquenessThreshold,
        pc.minSegment, pc.maxChain, pc.geometricTermClamp, pc.bijectivity);
    float M_c = rc.weight.y, M_h = min(rh.weight.y, pc.confidenceCap * M_c);
    // Shift 0: the canonical sample to the previous frame (its target there, for m_c);
    // shift 1: the history's sample here. One call site (code size).
    float t_c_prev = 0.0;
    ManifoldSample s_h = rh.s;
    vec3 F_h = vec3(0.0);
    uint attempts = 0u, success = 0u;
    for (uint it = 0u; it < 2u; ++it) {
        bool to_prev = it == 0u;
        ManifoldReservoir src = to_prev ? rc : rh;
        if (!(src.weight.x > 0.0)) continue;
        ManifoldSample t;
        vec3 F;
        attempts += 1u;
        bool ok = manifold_shift(src.s, src.receiver, !to_prev, to_prev ? rh.receiver : rc.receiver,
                                 to_prev, ss, t, F);
        if (!ok) continue;
        success += 1u;
        if (to_prev) {
            t_c_prev = luminance(F);
        } else {
            s_h = t;
            F_h = F;
        }
    }
    // Generalized balance heuristic, Jacobian 1 (shift.glsl).
    float p_c = rc.F.w, p_h_here = luminance(F_h);
    float m_c = p_c > 0.0 ? mis_balance2(M_c, p_c, M_h, t_c_prev) : 0.0;
    float m_h = p_h_here > 0.0 ? mis_balance2(M_h, rh.F.w, M_c, p_h_here) : 0.0;
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x7E3A11C5u);
    ManifoldReservoir r = rc;
    float w_sum = 0.0;
    manifold_reservoir_take(w_sum, m_c * p_c * rc.weight.x, rng_next(rng));
    if (manifold_reservoir_take(w_sum, m_h * p_h_here * rh.weight.x, rng_next(rng))) {
        r.s = s_h;
        r.F = vec4(F_h, p_h_here);
    }
    manifold_reservoir_finalize(r, w_sum);
    r.weight.y = M_c + M_h;
    manifold_reuse_finish(pixel, index, r, attempts, success);
}
