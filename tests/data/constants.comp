#version 460
// Test kernel (passes/common/tests/test_common_passes.cpp): copies every ComputePass constant, standard
// push-constant member, define and HAS_<port> flag into a buffer so the test can read them.
layout(local_size_x = 1) in;
layout(std430) writeonly buffer Values { float values[]; };
#if HAS_MASK
layout(r32f) uniform writeonly image2D maskImage;
#endif
layout(push_constant) uniform Params {
    float gain;
    int radius;
    uint samples;
    bool flip;
    vec2 offset;
    vec3 tint;
    float afterTint;  // packs into tint's 16-byte slot
    vec4 plane;
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    values[32 + i] = float(i) + 1.0;  // one slot per dispatched thread
    if (i != 0u) return;
    values[0] = pc.gain;
    values[1] = float(pc.radius);
    values[2] = float(pc.samples);
    values[3] = pc.flip ? 1.0 : 0.0;
    values[4] = pc.offset.x;
    values[5] = pc.offset.y;
    values[6] = pc.tint.x;
    values[7] = pc.tint.y;
    values[8] = pc.tint.z;
    values[9] = pc.afterTint;
    values[10] = pc.plane.x;
    values[11] = pc.plane.y;
    values[12] = pc.plane.z;
    values[13] = pc.plane.w;
    values[14] = float(pc.frameSize.x);
    values[15] = float(pc.frameSize.y);
    values[16] = float(pc.frameIndex);
    values[17] = float(pc.seed);
    values[18] = float(SCALE_DEFINE);
    values[19] = float(HAS_MASK);
    values[20] = float(gl_NumWorkGroups.x);
}
