// Multiple importance sampling heuristics (Veach 1997, Sec. 9.2).
#ifndef LOOM_MIS_GLSL
#define LOOM_MIS_GLSL

const uint MIS_BALANCE = 0u;
const uint MIS_POWER = 1u;

// Weight of technique a against b (one sample each); pdfs in the same measure.
float mis_weight(float pdf_a, float pdf_b, uint heuristic) {
    if (heuristic == MIS_POWER) {
        pdf_a *= pdf_a;
        pdf_b *= pdf_b;
    }
    return pdf_a > 0.0 ? pdf_a / (pdf_a + pdf_b) : 0.0;
}

#endif
