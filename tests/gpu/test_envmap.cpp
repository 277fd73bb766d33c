// Environment-map importance sampling (core/scene/EnvMapDistribution + shaders/lib/envmap.glsl):
// the CPU tables, and a chi-square goodness-of-fit test of envmap_sample against envmap_pdf on
// a synthetic lat-long map with a bright spot and black regions, for an unrotated and a
// rotated map packed into the same buffer.
#include <gtest/gtest.h>

#include "tests/support/Chi2.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "core/gpu/Context.h"
#include "core/scene/EnvMapDistribution.h"
#include "core/shader/ShaderCompiler.h"

namespace {

using namespace loom;
using scene::EnvMapDistribution;

constexpr double kPi = 3.14159265358979323846;
constexpr uint32_t kWidth = 64, kHeight = 32;
// Bright spot: a Gaussian of this peak radiance and width (texels) around texel (kSpotI, kSpotJ).
constexpr int kSpotI = 20, kSpotJ = 10;
constexpr double kSpotPeak = 400.0, kSpotSigma = 1.5;

// Sky gradient, a bright spot, a black rectangle inside lit rows and fully black rows.
std::vector<float> syntheticMap() {
    std::vector<float> rgba(size_t(kWidth) * kHeight * 4);
    for (uint32_t j = 0; j < kHeight; ++j) {
        for (uint32_t i = 0; i < kWidth; ++i) {
            const double di = double(i) - kSpotI, dj = double(j) - kSpotJ;
            const double spot =
                kSpotPeak * std::exp(-(di * di + dj * dj) / (2.0 * kSpotSigma * kSpotSigma));
            double sky = 0.05 + 0.2 * double(j) / kHeight;
            const bool black = (i >= 40 && i < 48 && j >= 5 && j < 9) || (j >= 26 && j < 29);
            if (black) sky = 0.0;
            float* t = &rgba[4 * (j * kWidth + i)];
            t[0] = float(black ? 0.0 : sky + spot);
            t[1] = float(black ? 0.0 : 0.8 * sky + 0.9 * spot);
            t[2] = float(black ? 0.0 : 1.5 * sky + 0.7 * spot);
            t[3] = 1.0f;
        }
    }
    return rgba;
}

double luminance(const float* t) {
    return 0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2];
}

// One context, compiler, pipelines and the two packed maps for every test in this file.
class EnvGpu {
public:
    static EnvGpu& get() {
        static EnvGpu g;
        return g;
    }
    gpu::Context& ctx() { return *mCtx; }
    const std::vector<EnvMapDistribution>& maps() const { return mMaps; }
    const std::vector<float>& texels() const { return mTexels; }
    const gpu::ComputePipeline& pipeline(const std::string& kernel) {
        auto& p = mPipelines[kernel];
        if (!p) {
            auto compiled = mCompiler->compile(std::string(LOOM_TEST_DATA) + "/" + kernel);
            p = mCtx->createPipeline(compiled->spirv, compiled->reflection, kernel);
        }
        return *p;
    }
    // Runs a kernel whose outputs are vec4 buffers; returns them in binding-name order.
    std::vector<std::vector<glm::vec4>> run(const std::string& kernel, gpu::Bindings bindings,
                                            const std::vector<std::string>& outputs,
                                            const std::map<std::string, uint32_t>& push,
                                            uint32_t count) {
        const auto& pipe = pipeline(kernel);
        std::vector<std::shared_ptr<gpu::Buffer>> outs;
        for (const auto& name : outputs) {
            outs.push_back(mCtx->createBuffer(count * sizeof(glm::vec4), name));
            bindings.set(name, outs.back());
        }
        scene::bindEnvMaps(bindings, mEnvBuffer);
        gpu::PushConstants pc(pipe);
        for (const auto& [name, value] : push) pc.set(name, value);
        auto cmd = mCtx->beginCommands();
        cmd->dispatchThreads(pipe, bindings, &pc, count);
        mCtx->submit(*cmd);
        std::vector<std::vector<glm::vec4>> result;
        for (const auto& b : outs) {
            result.emplace_back(count);
            mCtx->downloadBuffer(*b, result.back().data(), count * sizeof(glm::vec4));
        }
        return result;
    }
    std::shared_ptr<gpu::Buffer> upload(const std::vector<glm::vec4>& data) {
        auto b = mCtx->createBuffer(data.size() * sizeof(glm::vec4), "upload");
        mCtx->uploadBuffer(*b, data.data(), data.size() * sizeof(glm::vec4));
        return b;
    }

private:
    EnvGpu() : mTexels(syntheticMap()) {
        mCtx = gpu::Context::create();
        mCompiler = std::make_unique<ShaderCompiler>(
            std::vector<std::string>{std::string(LOOM_SOURCE_DIR) + "/shaders", LOOM_TEST_DATA},
            mCtx->cacheDir());
        // Map 1 is rotated: envmap.glsl must apply toWorld when sampling and its inverse when
        // evaluating.
        glm::mat4 rot = glm::rotate(glm::mat4(1.0f), 0.6f, glm::vec3(1.0f, 0.0f, 0.0f));
        rot = glm::rotate(rot, 1.1f, glm::vec3(0.0f, 1.0f, 0.0f));
        mMaps.emplace_back(mTexels.data(), kWidth, kHeight);
        mMaps.emplace_back(mTexels.data(), kWidth, kHeight, rot);
        mEnvBuffer = scene::packEnvMaps(*mCtx, mMaps);
    }
    std::shared_ptr<gpu::Context> mCtx;
    std::unique_ptr<ShaderCompiler> mCompiler;
    std::map<std::string, std::shared_ptr<gpu::ComputePipeline>> mPipelines;
    std::vector<float> mTexels;
    std::vector<EnvMapDistribution> mMaps;
    std::shared_ptr<gpu::Buffer> mEnvBuffer;
};

// ---------------------------------------------------------------------------------------------
// Chi-square helpers: tests/support/Chi2.h.
using loom::test::Chi2Result;
using loom::test::chi2;

// ---------------------------------------------------------------------------------------------

TEST(EnvMapDistribution, Tables) {
    const auto& texels = EnvGpu::get().texels();
    const EnvMapDistribution d(texels.data(), kWidth, kHeight);
    const auto& data = d.distribution();
    const size_t H = kHeight, W = kWidth;
    ASSERT_EQ(data.size(), 3 * H + 1 + 2 * H * W);
    // CDFs: monotone from 0 to exactly 1.
    auto checkCdf = [](const float* cdf, size_t n) {
        EXPECT_EQ(cdf[0], 0.0f);
        EXPECT_EQ(cdf[n], 1.0f);
        for (size_t i = 0; i < n; ++i) EXPECT_LE(cdf[i], cdf[i + 1]);
    };
    checkCdf(&data[H], H);
    for (size_t j = 0; j < H; ++j) checkCdf(&data[2 * H + 1 + H * W + j * (W + 1)], W);
    // Texel probabilities: proportional to luminance x sin(theta), summing to one.
    double norm = 0.0, total = 0.0;
    for (size_t j = 0; j < H; ++j)
        for (size_t i = 0; i < W; ++i)
            norm += luminance(&texels[4 * (j * W + i)]) * std::sin(kPi * (j + 0.5) / H);
    for (size_t j = 0; j < H; ++j) {
        for (size_t i = 0; i < W; ++i) {
            const double p = d.pdfUv({(i + 0.5) / W, (j + 0.5) / H}) / double(W * H);
            const double ref =
                luminance(&texels[4 * (j * W + i)]) * std::sin(kPi * (j + 0.5) / H) / norm;
            EXPECT_NEAR(p, ref, 1e-6 * std::max(ref, 1e-3)) << i << ", " << j;
            total += p;
        }
    }
    EXPECT_NEAR(total, 1.0, 1e-5);
    // Mean luminance over the sphere, against a fine quadrature of the nearest-texel lookup.
    double power = 0.0;
    const int n = 1024;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const glm::dvec2 uv((a + 0.5) / n, (b + 0.5) / n);
            const size_t i = size_t(uv.x * W), j = size_t(uv.y * H);
            power += luminance(&texels[4 * (j * W + i)]) * 2.0 * kPi * kPi * std::sin(kPi * uv.y) /
                     (double(n) * n);
        }
    EXPECT_NEAR(d.averageLuminance(), power / (4.0 * kPi), 1e-4 * power);
    // Direction <-> uv round trip (Mitsuba convention: uv (0, 0.5) looks down -z).
    const glm::dvec3 forward = EnvMapDistribution::direction({0.0, 0.5});
    EXPECT_NEAR(forward.z, -1.0, 1e-12);
    for (double u : {0.1, 0.45, 0.8})
        for (double v : {0.2, 0.5, 0.9}) {
            const glm::dvec2 uv = EnvMapDistribution::uv(EnvMapDistribution::direction({u, v}));
            EXPECT_NEAR(uv.x, u, 1e-12);
            EXPECT_NEAR(uv.y, v, 1e-12);
        }
}

TEST(EnvMapDistribution, RejectsEmptyTextures) {
    scene::Texture t;
    t.name = "sky";
    EXPECT_THROW(EnvMapDistribution d(t), std::invalid_argument);
}

// Samples binned by the (u, v) of toLocal * wi into half-texel cells (2W x 2H); expected counts
// integrate envmap_pdf (solid angle) times the Jacobian 2 pi^2 sin(theta) over each cell with the
// 2 x 2 Gauss-Legendre rule (exact: pdf x sin(theta) is constant per texel).
TEST(EnvMapSampling, ChiSquare) {
    EnvGpu& g = EnvGpu::get();
    constexpr uint32_t kN = 1u << 20;
    constexpr uint32_t kCu = 2 * kWidth, kCv = 2 * kHeight;
    const double alpha = 1.0 - std::pow(1.0 - 0.01, 1.0 / g.maps().size());  // Sidak
    // Quadrature nodes (world directions are per map).
    const double gl[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
    std::vector<glm::dvec2> nodes;
    std::vector<int> nodeCell;
    for (uint32_t cv = 0; cv < kCv; ++cv)
        for (uint32_t cu = 0; cu < kCu; ++cu)
            for (int a = 0; a < 2; ++a)
                for (int b = 0; b < 2; ++b) {
                    nodes.emplace_back((cu + gl[a]) / kCu, (cv + gl[b]) / kCv);
                    nodeCell.push_back(int(cv * kCu + cu));
                }
    for (uint32_t index = 0; index < g.maps().size(); ++index) {
        SCOPED_TRACE(::testing::Message() << "map " << index);
        const EnvMapDistribution& map = g.maps()[index];
        const glm::dmat3 toWorld(map.toWorld()), toLocal = glm::transpose(toWorld);
        const auto out = g.run("envmap_sample.comp", {}, {"SampleBuffer", "CheckBuffer"},
                               {{"count", kN}, {"seed", 5u + index}, {"index", index}}, kN);
        const auto& samples = out[0];
        const auto& checks = out[1];

        std::vector<double> observed(kCu * kCv, 0.0);
        size_t pdfMismatch = 0, radianceMismatch = 0, failed = 0, inSpot = 0;
        double maxPdfErr = 0.0;
        for (uint32_t s = 0; s < kN; ++s) {
            const glm::vec4 x = samples[s];
            if (!(x.w > 0.0f)) {
                ++failed;
                continue;
            }
            const glm::dvec3 local = toLocal * glm::dvec3(glm::vec3(x));
            const glm::dvec2 uv = EnvMapDistribution::uv(local);
            const uint32_t cu = std::min(uint32_t(uv.x * kCu), kCu - 1);
            const uint32_t cv = std::min(uint32_t(uv.y * kCv), kCv - 1);
            observed[cv * kCu + cu] += 1.0;
            // The sampled pdf is envmap_pdf at the sampled direction and the CPU reference;
            // texel edges may round to the neighbour (measure zero), hence the count below.
            const double err = std::abs(double(checks[s].x) - x.w) / x.w;
            maxPdfErr = std::max(maxPdfErr, err);
            const double cpu = map.pdfDirection(local);
            if (err > 1e-4 || std::abs(cpu - x.w) > 1e-3 * cpu) ++pdfMismatch;
            // envmap_eval returns the radiance of the texel containing the direction.
            const size_t ti = std::min(size_t(uv.x * kWidth), size_t(kWidth - 1));
            const size_t tj = std::min(size_t(uv.y * kHeight), size_t(kHeight - 1));
            const float* t = &g.texels()[4 * (tj * kWidth + ti)];
            for (int c = 0; c < 3; ++c)
                if (std::abs(checks[s][1 + c] - t[c]) > 1e-5f * std::max(1.0f, t[c]))
                    ++radianceMismatch;
            if (std::abs(int(ti) - kSpotI) <= 2 && std::abs(int(tj) - kSpotJ) <= 2) ++inSpot;
        }
        // u.y == 0 exactly (2^-24 per sample) lands on the pole, where the pdf is 0.
        EXPECT_LE(failed, kN / 100000);
        EXPECT_LE(pdfMismatch, kN / 100000) << "max relative pdf error " << maxPdfErr;
        EXPECT_LE(radianceMismatch, kN / 100000);

        // Expected counts from the GPU pdf on the quadrature nodes.
        std::vector<glm::vec4> dirs;
        std::vector<double> jac;
        for (const auto& uv : nodes) {
            const glm::dvec3 local = EnvMapDistribution::direction(uv);
            dirs.emplace_back(glm::vec3(toWorld * local), 0.0f);
            jac.push_back(2.0 * kPi * kPi * std::sin(kPi * uv.y) / (4.0 * kCu * kCv));
        }
        gpu::Bindings b;
        b.set("DirBuffer", g.upload(dirs));
        const auto pdfs =
            g.run("envmap_eval.comp", b, {"ResultBuffer"},
                  {{"count", uint32_t(dirs.size())}, {"index", index}}, uint32_t(dirs.size()))[0];
        std::vector<double> expected(kCu * kCv, 0.0);
        for (size_t k = 0; k < nodes.size(); ++k)
            expected[nodeCell[k]] += double(kN) * pdfs[k].x * jac[k];
        const double total = std::accumulate(expected.begin(), expected.end(), 0.0);
        EXPECT_NEAR(total, double(kN), 1e-4 * kN) << "envmap_pdf does not integrate to one";

        const Chi2Result r = chi2(observed, expected);
        std::printf(
            "[chi2] envmap %u (%s) chi2=%.1f dof=%d p=%.4f, %.1f%% of samples in the "
            "spot\n",
            index, index == 0 ? "identity" : "rotated", r.statistic, r.dof, r.pValue,
            100.0 * inSpot / kN);
        // A sample rotated into a world direction and back can cross a texel edge by rounding,
        // hence pbrt's leniency of N * 1e-5 samples in zero-expectation cells.
        EXPECT_LE(r.stray, kN * 1e-5) << "samples in black texels";
        EXPECT_GE(r.pValue, alpha) << "chi2 " << r.statistic << ", dof " << r.dof;
        // Importance sampling puts most samples where the energy is.
        EXPECT_GT(double(inSpot) / kN, 0.5);
    }
}

}  // namespace
