#pragma once
// FLIP, the perceptual image difference of Andersson et al. ("FLIP: A Difference Evaluator for
// Alternating Images", HPG 2020) and its HDR extension ("Visualizing Errors in Rendered High
// Dynamic Range Images", EG 2021): per-pixel errors in [0, 1] from a colour pipeline (contrast
// sensitivity filtering in YCxCz, Hunt-adjusted L*a*b*, HyAB distance) and a feature pipeline
// (edges and points of the achromatic channel). Used by the benchmarks (Lua loom.metrics.flip).
#include "core/image/Image.h"

namespace loom {

// Pixels per degree of the papers' default observer: a 0.7 m wide 4K monitor seen from 0.7 m.
constexpr double kFlipDefaultPpd = 0.7 * 3840.0 / 0.7 * 3.14159265358979323846 / 180.0;

// LDR-FLIP error map (one channel) of test against reference, both sRGB-encoded in [0, 1].
ImageData flipLdr(const ImageData& test, const ImageData& reference, double ppd = kFlipDefaultPpd);

// HDR-FLIP of linear images: LDR-FLIP at exposures from the start to the stop exposure computed
// from the reference (ACES tone curve, t = 0.85 at its maximum and at its median luminance),
// at least 2 exposures one stop apart, the per-pixel maximum.
ImageData flipHdr(const ImageData& test, const ImageData& reference, double ppd = kFlipDefaultPpd);

double meanOf(const ImageData& singleChannel);

}  // namespace loom
