// FLIP (core/image/Flip.cpp) against values derived by hand from the paper's definitions, and
// its properties: zero for identical images, locality, monotonic in noise, viewing distance.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/image/Flip.h"
#include "core/util/Error.h"

using namespace loom;

namespace {

ImageData constant(uint32_t w, uint32_t h, float r, float g, float b) {
    ImageData img = ImageData::make(w, h, 4, 1.0f);
    for (size_t p = 0; p < size_t(w) * h; ++p) {
        img.pixels[p * 4] = r;
        img.pixels[p * 4 + 1] = g;
        img.pixels[p * 4 + 2] = b;
    }
    return img;
}

}  // namespace

TEST(Flip, IdenticalImagesHaveZeroError) {
    ImageData a = constant(24, 20, 0.3f, 0.6f, 0.1f);
    EXPECT_EQ(meanOf(flipLdr(a, a)), 0.0);
    EXPECT_EQ(meanOf(flipHdr(a, a)), 0.0);
}

// Uniform images have no features, so FLIP is the redistributed colour error alone. White
// against black: Hunt-adjusted L*a*b* (100, 0, 0) and (0, 0, 0), HyAB 100. The maximum colour
// difference is between the Hunt-adjusted sRGB green and blue, from their standard CIELAB values
// (D65): green (87.735, -86.183, 83.179), blue (32.303, 79.197, -107.864).
TEST(Flip, UniformWhiteAgainstBlackMatchesTheDefinition) {
    auto hunt = [](double L, double a, double b) {
        return std::array<double, 3>{L, 0.01 * L * a, 0.01 * L * b};
    };
    auto g = hunt(87.735, -86.183, 83.179), bl = hunt(32.303, 79.197, -107.864);
    double cmax = std::pow(std::abs(g[0] - bl[0]) + std::hypot(g[1] - bl[1], g[2] - bl[2]), 0.7);
    double e = std::pow(100.0, 0.7);
    double expected =
        e < 0.4 * cmax ? 0.95 / (0.4 * cmax) * e : 0.95 + (e - 0.4 * cmax) / (0.6 * cmax) * 0.05;
    double got = meanOf(flipLdr(constant(16, 16, 1, 1, 1), constant(16, 16, 0, 0, 0)));
    EXPECT_NEAR(got, expected, 2e-4);
    // Below the redistribution knee: mid grey against a slightly lighter grey, L* from the sRGB
    // decoding (0.5 -> 0.21404 linear, L* 53.389; 0.52 -> 0.23302, L* 55.384).
    double small = std::pow(55.384 - 53.389, 0.7);
    double expectedSmall = 0.95 / (0.4 * cmax) * small;
    double gotSmall =
        meanOf(flipLdr(constant(16, 16, 0.52f, 0.52f, 0.52f), constant(16, 16, 0.5f, 0.5f, 0.5f)));
    EXPECT_NEAR(gotSmall, expectedSmall, 2e-3 * expectedSmall + 1e-4);
}

// A difference in one spot leaves pixels farther than the filters' reach at exactly 0, and
// the error is largest at the spot.
TEST(Flip, ErrorsStayLocal) {
    ImageData ref = constant(64, 64, 0.4f, 0.4f, 0.4f), test = ref;
    for (uint32_t y = 30; y < 34; ++y)
        for (uint32_t x = 30; x < 34; ++x) test.at(x, y, 0) = 0.9f;
    ImageData e = flipLdr(test, ref);
    EXPECT_GT(e.at(31, 31, 0), 0.3f);
    EXPECT_EQ(e.at(2, 2, 0), 0.0f);
    EXPECT_EQ(e.at(61, 5, 0), 0.0f);
    EXPECT_GT(e.at(31, 31, 0), e.at(40, 31, 0));
}

// More noise, more error; seen from farther away (more pixels per degree), less.
TEST(Flip, GrowsWithNoiseAndShrinksWithDistance) {
    ImageData ref = constant(48, 48, 0.3f, 0.35f, 0.4f);
    std::mt19937 rng(7);
    std::normal_distribution<float> n(0.0f, 1.0f);
    std::vector<float> noise(ref.pixels.size());
    for (float& v : noise) v = n(rng);
    double previous = 0.0;
    for (float sigma : {0.01f, 0.03f, 0.1f}) {
        ImageData t = ref;
        for (size_t i = 0; i < t.pixels.size(); ++i)
            if (i % 4 != 3) t.pixels[i] = std::max(0.0f, t.pixels[i] + sigma * noise[i]);
        double f = meanOf(flipHdr(t, ref));
        EXPECT_GT(f, previous) << "sigma " << sigma;
        previous = f;
        if (sigma == 0.1f) {
            EXPECT_LT(meanOf(flipHdr(t, ref, 4.0 * kFlipDefaultPpd)), f);
        }
    }
}

TEST(Flip, MismatchedSizesAreAnError) {
    EXPECT_THROW(flipLdr(constant(8, 8, 0, 0, 0), constant(8, 9, 0, 0, 0)), UserError);
}
