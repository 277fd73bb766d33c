// Multiple importance sampling heuristics (Veach 1997, Sec. 9.2).
#ifndef LOOM_MIS_GLSL
#define LOOM_MIS_GLSL

// Heuristics: MIS_HEURISTIC_BALANCE, MIS_HEURISTIC_POWER (registered shader enum, defined for
// every kernel from the C++ declaration in core/shader/ShaderEnums.cpp).

// Weight of technique a against b (one sample each); pdfs in the same measure.
float mis_weight(float pdf_a, float pdf_b, uint heuristic) {
    if (heuristic == MIS_HEURISTIC_POWER) {
        pdf_a *= pdf_a;
        pdf_b *= pdf_b;
    }
    return pdf_a > 0.0 ? pdf_a / (pdf_a + pdf_b) : 0.0;
}

#endif
