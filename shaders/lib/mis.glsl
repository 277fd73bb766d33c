// Multiple importance sampling heuristics (Veach 1997, Sec. 9.2), for combining sampling
// techniques inside a path (NEE vs BSDF, integrator/nee.glsl) and resampling techniques in reuse
// (restir/reuse_mis.glsl).
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

// Generalized balance heuristic: a technique's weighted density (confidence times target for
// resampling, Lin et al. 2022 Eq. 11) over the sum of all techniques' (0 when none has any).
float mis_balance(float own, float sum) { return sum > 0.0 ? own / sum : 0.0; }

// Two techniques: weight of technique a for a sample whose targets are t_a (own) and t_b
// (shifted to b), with confidences M_a, M_b.
float mis_balance2(float M_a, float t_a, float M_b, float t_b) {
    return mis_balance(M_a * t_a, M_a * t_a + M_b * t_b);
}

#endif
