#version 460
// The cheapest pass a graph can hold: one thread writes one texel. Measures executor overhead.
layout(local_size_x = 1) in;
layout(r32f) uniform image2D target;
layout(push_constant) uniform Params { uint frameIndex; } pc;
void main() { imageStore(target, ivec2(0), vec4(float(pc.frameIndex))); }
