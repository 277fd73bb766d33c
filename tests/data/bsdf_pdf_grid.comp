#version 460
// Test kernel (tests/gpu/test_bsdf.cpp): bsdf_pdf on the tensor grid of quadrature nodes
// (theta_i, phi_j) used to integrate the pdf over the chi-square cells.
#include "lib/bsdf.glsl"

layout(local_size_x = 64) in;
layout(std430) readonly buffer MaterialBuffer { Material materials[]; };
layout(std430) readonly buffer ThetaBuffer { vec2 thetas[]; };  // cos, sin
layout(std430) readonly buffer PhiBuffer { vec2 phis[]; };      // cos, sin
layout(std430) writeonly buffer PdfBuffer { float pdfs[]; };
layout(push_constant) uniform Params {
    vec3 wo;
    uint thetaCount;
    uint phiCount;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.thetaCount * pc.phiCount) return;
    vec2 t = thetas[i / pc.phiCount], p = phis[i % pc.phiCount];
    pdfs[i] = bsdf_pdf(materials[0], pc.wo, vec3(t.y * p.x, t.y * p.y, t.x));
}
