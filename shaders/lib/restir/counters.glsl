// ReSTIR PT shift statistics (attempts / successes by kind, rays), read back by the passes for
// Lua and the inspector (passes/ReSTIRPTInitial/PathReservoir.h, RestirCounters). Only kernels
// that shift include this file: it declares the buffer.
#ifndef LOOM_RESTIR_COUNTERS_GLSL
#define LOOM_RESTIR_COUNTERS_GLSL

layout(std430) buffer RestirCounters {
    uint shift_attempts_reconnect;
    uint shift_success_reconnect;
    uint shift_attempts_replay;
    uint shift_success_replay;
    uint shift_rays;  // rays traced by shifts (and by the domain changes of primary_shift.glsl)
    uint shift_max_bvh_iterations;  // most traversal steps of one invocation (bvh.glsl limit)
};

#endif
