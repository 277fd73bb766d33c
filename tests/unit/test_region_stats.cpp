// The region statistics every unbiasedness test compares with (tests/support/RegionStats.h).
#include <gtest/gtest.h>

#include <random>

#include "tests/support/RegionStats.h"

using namespace loom;
using namespace loom::test;

namespace {

ImageData constant(float v) {
    ImageData img = ImageData::make(4, 4, 4, 1.0f);
    for (size_t p = 0; p < 16; ++p)
        for (int c = 0; c < 3; ++c) img.pixels[p * 4 + c] = v;
    return img;
}

}  // namespace

// A region that both estimators compute without noise has a standard error of 0. Two float
// paths to the same value (-0.661674976 against -0.661674968 in ReSTIR G-PT's sky) must not
// read as |z| = 8847.
TEST(RegionStats, NoiselessRegionsDifferingByRoundingAgree) {
    RegionStats a(1), b(1);
    for (int s = 0; s < 96; ++s) {
        a.add(constant(-0.661674976f));
        b.add(constant(std::nextafter(-0.661674976f, 0.0f)));
    }
    EXPECT_LT(maxZ(a, b), 1.0);
}

// ...while a real difference between noiseless regions, or one within noise, still shows.
TEST(RegionStats, RealDifferencesStillShow) {
    RegionStats a(1), b(1);
    for (int s = 0; s < 96; ++s) {
        a.add(constant(0.5f));
        b.add(constant(0.5f * 1.001f));
    }
    EXPECT_GT(maxZ(a, b), 100.0);
    std::mt19937 rng(3);
    std::normal_distribution<float> noise(0.0f, 0.01f);
    RegionStats c(1), d(1);
    for (int s = 0; s < 400; ++s) {
        c.add(constant(0.5f + noise(rng)));
        d.add(constant(0.505f + noise(rng)));
    }
    EXPECT_GT(maxZ(c, d), 5.0);  // 0.005 / (0.01 sqrt(2 / 400)) = 7.1
}
