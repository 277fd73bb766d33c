#pragma once
// Region means of images with their standard errors, for statistical comparisons of estimators:
// each added image must be an independent estimate (one frame, or the mean of one independent
// sequence of frames), so the spread of the added values gives the standard error.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/image/Image.h"

namespace loom::test {

// regions x regions blocks, three channels each.
struct RegionStats {
    int regions;
    std::vector<double> sum, sum2;
    int frames = 0;
    explicit RegionStats(int r) : regions(r), sum(r * r * 3, 0.0), sum2(r * r * 3, 0.0) {}
    // skip: optional per-pixel mask (non-zero: left out of its region's mean).
    void add(const ImageData& img, const std::vector<uint8_t>* skip = nullptr) {
        std::vector<double> m(regions * regions * 3, 0.0);
        std::vector<int> count(regions * regions, 0);
        for (uint32_t y = 0; y < img.height; ++y)
            for (uint32_t x = 0; x < img.width; ++x) {
                if (skip && (*skip)[y * img.width + x]) continue;
                int r = int(y * regions / img.height) * regions + int(x * regions / img.width);
                for (int c = 0; c < 3; ++c) m[r * 3 + c] += img.at(x, y, c);
                ++count[r];
            }
        for (size_t i = 0; i < m.size(); ++i) {
            double v = count[i / 3] > 0 ? m[i] / count[i / 3] : 0.0;
            sum[i] += v;
            sum2[i] += v * v;
        }
        ++frames;
    }
    double mean(size_t i) const { return sum[i] / frames; }
    double stderr2(size_t i) const {
        double mu = mean(i);
        double var = (sum2[i] / frames - mu * mu) * frames / (frames - 1.0);
        return std::max(var, 0.0) / frames;
    }
};

// Largest |z| between two estimates of the same region means.
inline double maxZ(const RegionStats& a, const RegionStats& b, double* worstA = nullptr,
                   double* worstB = nullptr) {
    double worst = 0.0;
    for (size_t i = 0; i < a.sum.size(); ++i) {
        // A region both sides compute without noise (the same deterministic value in every
        // sequence) has se = 0: float rounding alone (1e-8 relative) would read as a huge z.
        double scale = std::max(std::abs(a.mean(i)), std::abs(b.mean(i)));
        double se = std::sqrt(a.stderr2(i) + b.stderr2(i));
        double z = std::abs(a.mean(i) - b.mean(i)) / std::max(se, 1e-6 * scale + 1e-12);
        if (z > worst) {
            worst = z;
            if (worstA) *worstA = a.mean(i);
            if (worstB) *worstB = b.mean(i);
        }
    }
    return worst;
}

}  // namespace loom::test
