#pragma once
// The images every gradient estimator of this family writes (GradientPathTracer,
// GradientAfterReSTIR, PairedPixelResolve), declared once: what PoissonReconstruct and the
// graphs' emission add-back read.
#include <string>

#include "core/graph/Pass.h"

namespace loom::gradient {

// primal: what this estimator's primal is (the emission at the primary hit is left out).
inline void reflectGradientImages(PassReflection& r, const std::string& primal) {
    r.outputTexture("primal", gpu::Format::RGBA32F)
        .doc(primal + ", without the emission seen at the primary hit");
    r.outputTexture("dx", gpu::Format::RGBA32F)
        .doc("estimate of I(p + e_x) - I(p), without that emission; 0 in the last column");
    r.outputTexture("dy", gpu::Format::RGBA32F)
        .doc("estimate of I(p + e_y) - I(p), without that emission; 0 in the last row");
    r.outputTexture("direct", gpu::Format::RGBA32F)
        .doc(
            "emission seen at the primary hit (environment on a miss), added back after the solve");
    r.outputTexture("color", gpu::Format::RGBA32F).optional().doc("primal + direct");
}

}  // namespace loom::gradient
