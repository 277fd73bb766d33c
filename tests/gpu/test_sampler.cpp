// The padded Sobol sampler (shaders/lib/rng.glsl, RNG_SOBOL; PathTracer's sampler = sobol):
// over a pixel's samples every 2D draw is a (0,m,2)-net and every 1D draw one point per
// stratum, and draws on different dimensions are uncorrelated. The path tracer's own tests
// (Lambert polygons, a planted dimension reuse) check the images it gives.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <glm/glm.hpp>
#include <vector>

#include "core/scene/SceneLoader.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/KernelColumns.h"

using namespace loom;

namespace {

// The 8 coordinates of dimensions 0..5 per (pixel, sample): 2D, 1D, 1D, 2D, 2D.
std::vector<std::array<double, 8>> draws(const std::vector<glm::vec4>& queries) {
    auto scene = scene::loadScene(test::sourcePath("scenes/cornell_box.json"));
    std::vector<std::vector<glm::vec4>> cols;
    for (const glm::vec4& q : queries) cols.push_back({q});
    auto out = test::runColumns(scene, "tests/data/rng_sobol.comp", cols, 2);
    std::vector<std::array<double, 8>> res;
    for (const auto& o : out)
        res.push_back({o[0].x, o[0].y, o[0].z, o[0].w, o[1].x, o[1].y, o[1].z, o[1].w});
    return res;
}

double correlation(const std::vector<std::array<double, 8>>& d, int a, int b) {
    double ma = 0, mb = 0, sab = 0, saa = 0, sbb = 0, n = double(d.size());
    for (const auto& x : d) ma += x[a] / n, mb += x[b] / n;
    for (const auto& x : d) {
        sab += (x[a] - ma) * (x[b] - mb);
        saa += (x[a] - ma) * (x[a] - ma);
        sbb += (x[b] - mb) * (x[b] - mb);
    }
    return sab / std::sqrt(saa * sbb);
}

}  // namespace

// Samples 0..255 and 256..511 of a pixel (aligned blocks of the sequence): each 2D draw has
// exactly one point in every elementary interval of area 1/256 (2^a by 2^(8-a) cells, a =
// 0..8), each 1D draw one point in every 1/256 stratum.
TEST(Sampler, SobolDrawsAreNetsOverAPixelsSamples) {
    constexpr int kM = 8, kN = 1 << kM;
    std::vector<glm::vec4> q;
    for (auto [px, first, seed] : {std::array{3, 0, 0}, std::array{3, kN, 0}, std::array{17, 0, 9}})
        for (int i = 0; i < kN; ++i) q.push_back(glm::vec4(px, 5, first + i, seed));
    auto d = draws(q);
    for (int block = 0; block < 3; ++block) {
        SCOPED_TRACE(::testing::Message() << "block " << block);
        auto at = [&](int i, int c) { return d[size_t(block * kN + i)][size_t(c)]; };
        for (int c : {2, 3}) {  // 1D draws
            std::vector<int> count(kN, 0);
            for (int i = 0; i < kN; ++i) ++count[size_t(at(i, c) * kN)];
            for (int k = 0; k < kN; ++k) ASSERT_EQ(count[size_t(k)], 1) << "1D dim " << c;
        }
        for (int c : {0, 4, 6}) {  // 2D draws: coordinates c, c + 1
            for (int a = 0; a <= kM; ++a) {
                int nx = 1 << a, ny = 1 << (kM - a);
                std::vector<int> count(kN, 0);
                for (int i = 0; i < kN; ++i)
                    ++count[size_t(int(at(i, c + 1) * ny) * nx + int(at(i, c) * nx))];
                for (int k = 0; k < kN; ++k)
                    ASSERT_EQ(count[size_t(k)], 1)
                        << "2D coords " << c << ", cells " << nx << "x" << ny;
            }
        }
    }
}

// Over 64 pixels x 64 samples, no two coordinates of different dimensions correlate (|r| below
// 4.5 / sqrt(N), Bonferroni over the 26 pairs), and each coordinate's mean is 1/2. With the
// planted dimension reuse (LOOM_TEST_SOBOL_REUSE_DIMENSION) the 1D draw repeats the 2D draw's
// first coordinate, and the test sees it.
TEST(Sampler, SobolDimensionsAreUncorrelated) {
    std::vector<glm::vec4> q;
    for (int p = 0; p < 64; ++p)
        for (int i = 0; i < 64; ++i) q.push_back(glm::vec4(p % 8, p / 8, i, 1));
    auto d = draws(q);
    const double n = double(d.size()), bound = 4.5 / std::sqrt(n);
    const int dim[8] = {0, 0, 1, 2, 3, 3, 4, 4};
    for (int a = 0; a < 8; ++a) {
        double mean = 0;
        for (const auto& x : d) mean += x[size_t(a)] / n;
        EXPECT_NEAR(mean, 0.5, 4.5 * std::sqrt(1.0 / 12.0 / n)) << "coordinate " << a;
        for (int b = a + 1; b < 8; ++b)
            if (dim[a] != dim[b]) {
                EXPECT_LT(std::abs(correlation(d, a, b)), bound)
                    << "coordinates " << a << ", " << b;
            }
    }
    ::setenv("LOOM_SHADER_DEFINES", "LOOM_TEST_SOBOL_REUSE_DIMENSION=1", 1);
    auto planted = draws(q);
    ::unsetenv("LOOM_SHADER_DEFINES");
    EXPECT_GT(correlation(planted, 0, 2), 0.999);
}
