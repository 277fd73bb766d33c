// Shading library tests (shaders/lib/{fresnel,microfacet,bsdf}.glsl) on the GPU:
//  - chi-square goodness of fit of every non-delta sampling routine against its bsdf_pdf
//    (pbrt-v3 / Mitsuba style: (cos theta, phi) histogram vs the pdf integrated per cell,
//    low-expectation cells pooled, significance 0.01 with a Sidak correction over all cases),
//    with the per-sample check that the sampled f and pdf equal bsdf_eval and bsdf_pdf;
//  - delta lobes against analytic directions, weights and Fresnel choice frequencies;
//  - Fresnel and microfacet terms against CPU references and normalisation identities;
//  - white-furnace energy bounds and (generalised) reciprocity.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "core/gpu/Context.h"
#include "core/scene/MaterialGpu.h"
#include "core/shader/ShaderCompiler.h"
#include "tests/support/Chi2.h"

namespace {

using namespace loom;
using scene::BsdfType;
using scene::Material;

constexpr double kPi = 3.14159265358979323846;
// Azimuth of every incident direction in the tests: lobes sit around the plane of incidence,
// forward of it at phi = kWoPhi - pi.
constexpr double kWoPhi = 0.3;

// Flags and modes of bsdf.glsl.
constexpr uint32_t kReflection = 1, kTransmission = 2, kDiffuse = 4, kGlossy = 8, kDelta = 16,
                   kNull = 32;
constexpr uint32_t kRadiance = 0, kImportance = 1;

// ---------------------------------------------------------------------------------------------
// One Vulkan context, compiler and pipeline set shared by every test in this file.

class Gpu {
public:
    static Gpu& get() {
        static Gpu gpu;
        return gpu;
    }
    gpu::Context& ctx() { return *mCtx; }
    const gpu::ComputePipeline& pipeline(const std::string& kernel) {
        auto& p = mPipelines[kernel];
        if (!p) {
            auto compiled = mCompiler->compile(std::string(LOOM_TEST_DATA) + "/" + kernel);
            p = mCtx->createPipeline(compiled->spirv, compiled->reflection, kernel);
        }
        return *p;
    }
    template <class T>
    std::shared_ptr<gpu::Buffer> upload(const std::vector<T>& data, const std::string& name) {
        auto buffer = mCtx->createBuffer(data.size() * sizeof(T), name);
        mCtx->uploadBuffer(*buffer, data.data(), data.size() * sizeof(T));
        return buffer;
    }
    // Output buffers are reused across cases (allocating ~100 MB per chi-square case costs
    // more than the kernels on lavapipe).
    std::shared_ptr<gpu::Buffer> scratch(const std::string& name, size_t bytes) {
        auto& b = mScratch[name];
        if (!b || b->size() < bytes) b = mCtx->createBuffer(bytes, name);
        return b;
    }
    std::shared_ptr<gpu::Buffer> output(size_t count, const std::string& name) {
        return scratch(name, count * sizeof(glm::vec4));
    }
    std::vector<glm::vec4> download(const gpu::Buffer& buffer, size_t count) {
        std::vector<glm::vec4> out(count);
        mCtx->downloadBuffer(buffer, out.data(), count * sizeof(glm::vec4));
        return out;
    }
    void run(const gpu::ComputePipeline& pipe, const gpu::Bindings& bindings,
             const gpu::PushConstants& push, uint32_t threads) {
        auto cmd = mCtx->beginCommands();
        cmd->dispatchThreads(pipe, bindings, &push, threads);
        mCtx->submit(*cmd);
    }

private:
    Gpu() {
        mCtx = gpu::Context::create();
        mCompiler = std::make_unique<ShaderCompiler>(
            std::vector<std::string>{std::string(LOOM_SOURCE_DIR) + "/shaders", LOOM_TEST_DATA},
            mCtx->cacheDir());
    }
    std::shared_ptr<gpu::Context> mCtx;
    std::unique_ptr<ShaderCompiler> mCompiler;
    std::map<std::string, std::shared_ptr<gpu::ComputePipeline>> mPipelines;
    std::map<std::string, std::shared_ptr<gpu::Buffer>> mScratch;
};

// ---------------------------------------------------------------------------------------------
// Kernel wrappers.

struct SampleBatch {
    std::vector<glm::vec4> samples;  // wi, pdf
    std::vector<glm::vec4> values;   // f, flags bits
    std::vector<glm::vec4> checks;   // bsdf_eval(wi), bsdf_pdf(wi)
    std::vector<float> etas;         // BsdfSample.eta
    uint32_t flags(size_t i) const {
        uint32_t bits;
        std::memcpy(&bits, &values[i].w, sizeof(bits));
        return bits;
    }
};

SampleBatch sampleBsdf(const Material& material, glm::vec3 wo, uint32_t count, uint32_t mode,
                       uint32_t seed = 1) {
    Gpu& g = Gpu::get();
    const auto& pipe = g.pipeline("bsdf_sample.comp");
    auto mat = g.upload(std::vector<scene::MaterialGpu>{scene::packMaterial(material)}, "mat");
    auto samples = g.output(count, "samples"), values = g.output(count, "values"),
         checks = g.output(count, "checks");
    auto etas = g.scratch("etas", count * sizeof(float));
    gpu::Bindings b;
    b.set("MaterialBuffer", mat)
        .set("SampleBuffer", samples)
        .set("ValueBuffer", values)
        .set("CheckBuffer", checks)
        .set("EtaBuffer", etas);
    gpu::PushConstants pc(pipe);
    pc.set("wo", &wo.x, 3).set("count", count).set("seed", seed).set("mode", mode);
    g.run(pipe, b, pc, count);
    SampleBatch batch{g.download(*samples, count), g.download(*values, count),
                      g.download(*checks, count), std::vector<float>(count)};
    g.ctx().downloadBuffer(*etas, batch.etas.data(), count * sizeof(float));
    return batch;
}

// bsdf_eval (rgb) and bsdf_pdf (a) for pairs; one wo for all when wos.size() == 1.
std::vector<glm::vec4> evalBsdf(const Material& material, const std::vector<glm::vec4>& wos,
                                const std::shared_ptr<gpu::Buffer>& wis, uint32_t count,
                                uint32_t mode) {
    Gpu& g = Gpu::get();
    const auto& pipe = g.pipeline("bsdf_eval.comp");
    auto mat = g.upload(std::vector<scene::MaterialGpu>{scene::packMaterial(material)}, "mat");
    auto woBuf = g.upload(wos, "wos");
    auto out = g.output(count, "results");
    gpu::Bindings b;
    b.set("MaterialBuffer", mat)
        .set("WoBuffer", woBuf)
        .set("WiBuffer", wis)
        .set("ResultBuffer", out);
    gpu::PushConstants pc(pipe);
    pc.set("count", count).set("woCount", uint32_t(wos.size())).set("mode", mode);
    g.run(pipe, b, pc, count);
    return g.download(*out, count);
}

std::vector<glm::vec4> evalBsdf(const Material& material, const std::vector<glm::vec4>& wos,
                                const std::vector<glm::vec4>& wis, uint32_t mode) {
    return evalBsdf(material, wos, Gpu::get().upload(wis, "wis"), uint32_t(wis.size()), mode);
}

glm::vec3 sphericalDirection(double cosTheta, double phi) {
    const double s = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
    return glm::vec3(float(s * std::cos(phi)), float(s * std::sin(phi)), float(cosTheta));
}

// Incident direction at polar angle thetaDeg (> 90: below the surface), fixed azimuth.
glm::vec3 woAt(double thetaDeg) {
    return sphericalDirection(std::cos(thetaDeg * kPi / 180.0), kWoPhi);
}

// ---------------------------------------------------------------------------------------------
// Chi-square machinery.

using loom::test::gammaQ;
using loom::test::sidak;

struct Chi2Result : loom::test::Chi2Result {
    std::string error;  // non-empty: rejected before the statistic (samples in an empty cell)
};

// Rounding can put a handful of samples next to a zero-pdf boundary; more is an error.
Chi2Result chi2(const std::vector<double>& observed, const std::vector<double>& expected,
                double sampleCount) {
    Chi2Result r;
    static_cast<loom::test::Chi2Result&>(r) = loom::test::chi2(observed, expected);
    if (r.maxStray > sampleCount * 1e-5)
        r.error = "encountered " + std::to_string(r.maxStray) +
                  " samples in a cell with expected frequency 0";
    return r;
}

// (cos theta, phi) histogram grid, and the quadrature of the pdf over its cells: each cell is
// split into sub-rectangles integrated with the 2 x 2 Gauss-Legendre rule, uniform in theta
// (smooth at the poles, where cos theta is a singular coordinate) and in phi. The rule is open
// and every known discontinuity of the pdf is a sub-interval edge: the horizon, and for rough
// dielectrics the cone where the generalised half vector turns horizontal (the refracted pdf
// jumps there). Finer subdivisions where lobes are sharp: rows at the horizon, the poles and
// the discontinuity, and the forward azimuths, where grazing lobes are only ~2 alpha cos(theta_o)
// wide in phi.
struct Quadrature {
    static constexpr int kCos = 40, kPhi = 80;
    static constexpr int kSub = 6, kSubFine = 48;
    std::vector<glm::vec2> thetas, phis;  // (cos, sin) of each node
    std::vector<double> thetaWeights, phiWeights;
    std::vector<int> rows, cols;

    static int cellOf(const glm::vec3& w) {
        const double phi = std::atan2(double(w.y), double(w.x));
        const int c = std::clamp(int((double(w.z) + 1.0) * 0.5 * kCos), 0, kCos - 1);
        const int p = std::clamp(int((phi + kPi) / (2.0 * kPi) * kPhi), 0, kPhi - 1);
        return c * kPhi + p;
    }

    // Gauss-Legendre nodes (position, weight) of [a, b] split into `sub` intervals.
    static void nodes(double a, double b, int sub, std::vector<std::pair<double, double>>& out) {
        const double gl[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
        const double h = (b - a) / sub;
        for (int k = 0; k < 2 * sub; ++k) out.emplace_back(a + h * (k / 2 + gl[k % 2]), 0.5 * h);
    }

    // breakCos: cosines where the pdf is discontinuous (besides the horizon).
    explicit Quadrature(const std::vector<double>& breakCos) {
        for (int c = 0; c < kCos; ++c) {
            const double c0 = -1.0 + 2.0 * c / kCos, c1 = -1.0 + 2.0 * (c + 1) / kCos;
            bool fine = c <= 1 || c >= kCos - 2 || c == kCos / 2 - 1 || c == kCos / 2;
            // theta decreases with cos: the row spans [acos(c1), acos(c0)], split at breaks.
            std::vector<double> edges = {std::acos(c1)};
            for (double b : breakCos)
                if (b > c0 && b < c1) {
                    edges.push_back(std::acos(b));
                    fine = true;
                }
            edges.push_back(std::acos(c0));
            std::vector<std::pair<double, double>> ts;
            for (size_t e = 0; e + 1 < edges.size(); ++e)
                nodes(edges[e], edges[e + 1], fine ? kSubFine : kSub, ts);
            for (auto [theta, w] : ts) {
                thetas.emplace_back(std::cos(theta), std::sin(theta));
                thetaWeights.push_back(w * std::sin(theta));
                rows.push_back(c);
            }
        }
        const int forward = int(kWoPhi / (2.0 * kPi) * kPhi);  // bin of phi = kWoPhi - pi
        for (int p = 0; p < kPhi; ++p) {
            std::vector<std::pair<double, double>> ps;
            nodes(-kPi + 2.0 * kPi * p / kPhi, -kPi + 2.0 * kPi * (p + 1) / kPhi,
                  std::abs(p - forward) <= 2 ? kSubFine : kSub, ps);
            for (auto [phi, w] : ps) {
                phis.emplace_back(std::cos(phi), std::sin(phi));
                phiWeights.push_back(w);
                cols.push_back(p);
            }
        }
    }
};

// N x integral of bsdf_pdf over every cell of the grid.
std::vector<double> expectedCounts(const Material& material, glm::vec3 wo, double n,
                                   const Quadrature& q) {
    Gpu& g = Gpu::get();
    const auto& pipe = g.pipeline("bsdf_pdf_grid.comp");
    const uint32_t count = uint32_t(q.thetas.size() * q.phis.size());
    auto mat = g.upload(std::vector<scene::MaterialGpu>{scene::packMaterial(material)}, "mat");
    auto thetas = g.upload(q.thetas, "thetas"), phis = g.upload(q.phis, "phis");
    auto out = g.scratch("pdfs", count * sizeof(float));
    gpu::Bindings b;
    b.set("MaterialBuffer", mat)
        .set("ThetaBuffer", thetas)
        .set("PhiBuffer", phis)
        .set("PdfBuffer", out);
    gpu::PushConstants pc(pipe);
    pc.set("wo", &wo.x, 3)
        .set("thetaCount", uint32_t(q.thetas.size()))
        .set("phiCount", uint32_t(q.phis.size()));
    g.run(pipe, b, pc, count);
    std::vector<float> pdfs(count);
    g.ctx().downloadBuffer(*out, pdfs.data(), count * sizeof(float));
    std::vector<double> cells(Quadrature::kCos * Quadrature::kPhi, 0.0);
    for (size_t i = 0; i < q.thetas.size(); ++i)
        for (size_t j = 0; j < q.phis.size(); ++j)
            cells[q.rows[i] * Quadrature::kPhi + q.cols[j]] +=
                n * pdfs[i * q.phis.size() + j] * q.thetaWeights[i] * q.phiWeights[j];
    return cells;
}

struct Chi2Case {
    std::string name;
    Material material;
    double thetaDeg;  // wo polar angle (> 90: below the surface)
};

Material makeMaterial(BsdfType type, float alpha = 0.0f,
                      scene::Microfacet dist = scene::Microfacet::GGX) {
    Material m;
    m.type = type;
    m.alpha = alpha;
    m.distribution = dist;
    m.reflectance = glm::vec3(0.6f, 0.45f, 0.2f);
    m.eta = 1.5f;
    // Gold at (650, 550, 450) nm, roughly (Mitsuba's Au data).
    m.conductorEta = glm::vec3(0.143f, 0.374f, 1.442f);
    m.conductorK = glm::vec3(3.983f, 2.385f, 1.603f);
    return m;
}

std::vector<Chi2Case> chi2Cases() {
    using scene::Microfacet;
    std::vector<Chi2Case> cases;
    auto add = [&](const std::string& family, Material m, double theta) {
        char name[160];
        std::snprintf(name, sizeof(name), "%s %s a=%.2f theta=%.0f", family.c_str(),
                      m.distribution == Microfacet::GGX ? "ggx" : "beckmann", m.alpha, theta);
        cases.push_back({name, m, theta});
    };
    add("diffuse", makeMaterial(BsdfType::Diffuse), 30);
    Material twoSidedDiffuse = makeMaterial(BsdfType::Diffuse);
    twoSidedDiffuse.twoSided = true;
    add("diffuse-twosided", twoSidedDiffuse, 120);

    for (auto [a, thetas] : std::vector<std::pair<float, std::vector<double>>>{
             {0.1f, {0, 45, 85}}, {0.4f, {0, 60, 89}}, {0.9f, {30, 80}}})
        for (double t : thetas) add("roughconductor", makeMaterial(BsdfType::RoughConductor, a), t);
    for (auto [a, thetas] :
         std::vector<std::pair<float, std::vector<double>>>{{0.15f, {30, 80}}, {0.6f, {0, 70}}})
        for (double t : thetas)
            add("roughconductor", makeMaterial(BsdfType::RoughConductor, a, Microfacet::Beckmann),
                t);
    Material twoSidedConductor = makeMaterial(BsdfType::RoughConductor, 0.3f);
    twoSidedConductor.twoSided = true;
    add("roughconductor-twosided", twoSidedConductor, 140);

    // Inside the glass (theta > 90) the critical angle is 41.8 deg: 30 refracts, 60 is TIR.
    for (auto [a, thetas] : std::vector<std::pair<float, std::vector<double>>>{
             {0.15f, {20, 75, 150, 120}}, {0.5f, {0, 50, 88, 160, 110}}})
        for (double t : thetas)
            add("roughdielectric", makeMaterial(BsdfType::RoughDielectric, a), t);
    for (double t : {40.0, 130.0})
        add("roughdielectric", makeMaterial(BsdfType::RoughDielectric, 0.3f, Microfacet::Beckmann),
            t);

    for (double t : {10.0, 80.0}) add("plastic", makeMaterial(BsdfType::Plastic), t);
    for (auto [a, thetas] :
         std::vector<std::pair<float, std::vector<double>>>{{0.2f, {30, 85}}, {0.6f, {60}}})
        for (double t : thetas) add("roughplastic", makeMaterial(BsdfType::RoughPlastic, a), t);
    add("roughplastic", makeMaterial(BsdfType::RoughPlastic, 0.3f, Microfacet::Beckmann), 45);
    return cases;
}

struct SamplingReport {
    Chi2Result chi2;
    size_t checked = 0;     // non-delta samples compared with eval / pdf
    size_t mismatched = 0;  // ... whose weight (> 1e-4) or pdf (> 1e-2) differs, relative
    double maxWeightError = 0.0, maxPdfError = 0.0;
    size_t badEta = 0;  // samples whose BsdfSample.eta is wrong
};

constexpr uint32_t kChi2Samples = 1u << 20;

// Histogram of the sampled non-delta directions vs N * integral of bsdf_pdf over each cell.
// Samples that failed or chose a delta lobe form one more cell, expected N (1 - integral).
SamplingReport runSamplingCase(const Chi2Case& c) {
    const glm::vec3 wo = woAt(c.thetaDeg);
    const SampleBatch batch = sampleBsdf(c.material, wo, kChi2Samples, kRadiance);
    // Rough dielectrics: the refracted pdf jumps where the generalised half vector
    // eta wi + wo turns horizontal, wi.z = -wo.z / eta_rel.
    std::vector<double> breaks;
    if (c.material.type == BsdfType::RoughDielectric)
        breaks.push_back(wo.z > 0.0f ? -wo.z / c.material.eta : -wo.z * c.material.eta);
    std::vector<double> expected = expectedCounts(c.material, wo, kChi2Samples, Quadrature(breaks));

    const int cells = Quadrature::kCos * Quadrature::kPhi;
    std::vector<double> observed(cells + 1, 0.0);
    const double total = std::accumulate(expected.begin(), expected.end(), 0.0);
    expected.push_back(std::max(0.0, double(kChi2Samples) - total));
    SamplingReport report;
    for (size_t i = 0; i < batch.samples.size(); ++i) {
        const glm::vec4 s = batch.samples[i];
        if (!(s.w > 0.0f) || (batch.flags(i) & kDelta)) {
            observed[cells] += 1.0;
            continue;
        }
        const glm::vec3 wi(s);
        observed[Quadrature::cellOf(wi)] += 1.0;
        // Sampled f and pdf must be bsdf_eval and bsdf_pdf at wi. The weight f / pdf, what an
        // estimator uses, is held to 1e-4. The pdf alone only to 1e-2: near the critical angle
        // the half vector recomputed from a refracted wi is ill-conditioned in float (the
        // Jacobian has |wi.h| -> 0), which costs up to ~3e-3 relative on a few samples.
        const glm::vec4 chk = batch.checks[i];
        const double pdfErr = std::abs(double(chk.w) - s.w) / s.w;
        double wErr = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double ws = double(batch.values[i][k]) / s.w;
            const double we = chk.w > 0.0f ? double(chk[k]) / chk.w : 0.0;
            wErr = std::max(wErr, std::abs(ws - we) / std::max(std::abs(we), 1e-2));
        }
        // BsdfSample.eta: the IOR ratio crossed along wi, 1 for reflection.
        const double etaExpected = (batch.flags(i) & kTransmission)
                                       ? (wo.z > 0.0f ? c.material.eta : 1.0 / c.material.eta)
                                       : 1.0;
        if (std::abs(batch.etas[i] - etaExpected) > 1e-6) ++report.badEta;
        ++report.checked;
        report.maxPdfError = std::max(report.maxPdfError, pdfErr);
        report.maxWeightError = std::max(report.maxWeightError, wErr);
        if (!(pdfErr <= 1e-2) || !(wErr <= 1e-4)) ++report.mismatched;
    }
    report.chi2 = chi2(observed, expected, kChi2Samples);
    return report;
}

void runChi2Family(const std::string& family) {
    const auto cases = chi2Cases();
    const double alpha = sidak(int(cases.size()));
    int run = 0;
    for (const auto& c : cases) {
        if (c.name.rfind(family + " ", 0) != 0) continue;
        ++run;
        SCOPED_TRACE(c.name);
        const SamplingReport r = runSamplingCase(c);
        std::printf("[chi2] %-44s chi2=%9.1f dof=%4d p=%.4f  (weight err %.1e, pdf err %.1e)\n",
                    c.name.c_str(), r.chi2.statistic, r.chi2.dof, r.chi2.pValue, r.maxWeightError,
                    r.maxPdfError);
        EXPECT_TRUE(r.chi2.error.empty()) << r.chi2.error;
        EXPECT_GE(r.chi2.pValue, alpha)
            << "chi2 rejects the sampling routine: chi2 " << r.chi2.statistic << ", dof "
            << r.chi2.dof << ", p " << r.chi2.pValue << " < " << alpha;
        EXPECT_GT(r.checked, kChi2Samples / 4) << "too few valid non-delta samples";
        EXPECT_EQ(r.badEta, 0u) << "BsdfSample.eta differs from the crossed IOR ratio";
        EXPECT_EQ(r.mismatched, 0u) << "sampled f/pdf differ from bsdf_eval/bsdf_pdf: max "
                                       "weight error "
                                    << r.maxWeightError << ", max pdf error " << r.maxPdfError;
    }
    EXPECT_GT(run, 0) << "no chi2 case for " << family;
}

TEST(BsdfSampling, Diffuse) {
    runChi2Family("diffuse");
}
TEST(BsdfSampling, DiffuseTwoSided) {
    runChi2Family("diffuse-twosided");
}
TEST(BsdfSampling, RoughConductor) {
    runChi2Family("roughconductor");
}
TEST(BsdfSampling, RoughConductorTwoSided) {
    runChi2Family("roughconductor-twosided");
}
TEST(BsdfSampling, RoughDielectric) {
    runChi2Family("roughdielectric");
}
TEST(BsdfSampling, Plastic) {
    runChi2Family("plastic");
}
TEST(BsdfSampling, RoughPlastic) {
    runChi2Family("roughplastic");
}

// ---------------------------------------------------------------------------------------------
// Delta lobes: analytic directions, weights and choice frequencies.

// Two-sided p-value of a binomial count against probability p (normal approximation).
double binomialPValue(double hits, double n, double p) {
    const double sd = std::sqrt(n * p * (1.0 - p));
    if (sd == 0.0) return hits == n * p ? 1.0 : 0.0;
    return std::erfc(std::abs(hits - n * p) / sd / std::sqrt(2.0));
}

// Conductor Fresnel from the complex IOR n = eta + i k (Born & Wolf), in double.
double fresnelConductorReference(double cosI, double eta, double k) {
    using C = std::complex<double>;
    const C n(eta, k);
    const double sin2 = 1.0 - cosI * cosI;
    const C cosT = std::sqrt(n * n - sin2);  // n cos(theta_t)
    const C rs = (cosI - cosT) / (cosI + cosT);
    const C rp = (n * n * cosI - cosT) / (n * n * cosI + cosT);
    return 0.5 * (std::norm(rs) + std::norm(rp));
}

TEST(BsdfDelta, SmoothConductor) {
    Material m = makeMaterial(BsdfType::Conductor);
    m.specularReflectance = glm::vec3(0.9f, 0.8f, 0.7f);
    for (double theta : {0.0, 30.0, 60.0, 85.0, 89.5}) {
        SCOPED_TRACE(theta);
        const glm::vec3 wo = woAt(theta);
        const auto b = sampleBsdf(m, wo, 256, kRadiance);
        for (size_t i = 0; i < b.samples.size(); ++i) {
            ASSERT_EQ(b.flags(i), kReflection | kDelta);
            EXPECT_EQ(b.samples[i].w, 1.0f);
            EXPECT_NEAR(b.samples[i].x, -wo.x, 1e-6);
            EXPECT_NEAR(b.samples[i].y, -wo.y, 1e-6);
            EXPECT_NEAR(b.samples[i].z, wo.z, 1e-6);
            for (int k = 0; k < 3; ++k) {
                const double F =
                    fresnelConductorReference(wo.z, m.conductorEta[k], m.conductorK[k]);
                EXPECT_NEAR(b.values[i][k], m.specularReflectance[k] * F, 1e-4);
            }
            // Delta lobes are invisible to bsdf_eval and bsdf_pdf.
            EXPECT_EQ(b.checks[i], glm::vec4(0.0f));
        }
    }
}

TEST(BsdfDelta, SmoothDielectric) {
    Material m = makeMaterial(BsdfType::Dielectric);
    m.specularReflectance = glm::vec3(0.9f, 0.95f, 1.0f);
    m.specularTransmittance = glm::vec3(0.7f, 0.8f, 0.9f);
    const std::vector<double> thetas = {0, 30, 60, 85, 170, 140, 135, 110};  // > 90: inside
    const double alpha = sidak(int(2 * thetas.size()));
    constexpr uint32_t kN = 1u << 18;
    uint32_t seed = 7;  // independent random numbers for every frequency test
    for (double theta : thetas) {
        for (uint32_t mode : {kRadiance, kImportance}) {
            ++seed;
            SCOPED_TRACE(::testing::Message() << "theta " << theta << " mode " << mode);
            const glm::vec3 wo = woAt(theta);
            const bool inside = wo.z < 0.0f;
            const double eta = inside ? 1.0 / m.eta : m.eta;  // IOR ratio across from wo
            const double cosO = std::abs(double(wo.z));
            const double F = scene::fresnelDielectric(cosO, eta);
            // Snell in double: tangential part / eta, on the other side.
            const double sin2T = (1.0 - cosO * cosO) / (eta * eta);
            const auto b = sampleBsdf(m, wo, kN, mode, seed);
            double reflections = 0.0;
            for (size_t i = 0; i < b.samples.size(); ++i) {
                const uint32_t flags = b.flags(i);
                const glm::vec3 wi(b.samples[i]);
                const glm::vec3 w = glm::vec3(b.values[i]) / b.samples[i].w;
                ASSERT_TRUE(flags & kDelta);
                ASSERT_EQ(b.checks[i], glm::vec4(0.0f));
                if (flags & kReflection) {
                    reflections += 1.0;
                    ASSERT_NEAR(b.samples[i].w, F, 1e-5);
                    ASSERT_NEAR(wi.x, -wo.x, 1e-6);
                    ASSERT_NEAR(wi.y, -wo.y, 1e-6);
                    ASSERT_NEAR(wi.z, wo.z, 1e-6);
                    for (int k = 0; k < 3; ++k) ASSERT_NEAR(w[k], m.specularReflectance[k], 1e-5);
                    ASSERT_EQ(b.etas[i], 1.0f);
                } else {
                    ASSERT_EQ(flags, kTransmission | kDelta);
                    ASSERT_LT(sin2T, 1.0);
                    ASSERT_NEAR(b.samples[i].w, 1.0 - F, 1e-5);
                    ASSERT_NEAR(wi.x, -wo.x / eta, 1e-5);
                    ASSERT_NEAR(wi.y, -wo.y / eta, 1e-5);
                    ASSERT_NEAR(wi.z, (inside ? 1.0 : -1.0) * std::sqrt(1.0 - sin2T), 1e-5);
                    // Radiance is scaled by 1 / eta^2 when crossing into eta (Veach 1997 5.2).
                    const double scale = mode == kRadiance ? 1.0 / (eta * eta) : 1.0;
                    for (int k = 0; k < 3; ++k)
                        ASSERT_NEAR(w[k], m.specularTransmittance[k] * scale, 1e-5);
                    ASSERT_NEAR(b.etas[i], eta, 1e-6);
                }
            }
            const double p = binomialPValue(reflections, kN, F);
            std::printf("[delta] dielectric theta=%5.1f mode=%u F=%.5f freq=%.5f p=%.4f\n", theta,
                        mode, F, reflections / kN, p);
            EXPECT_GE(p, alpha) << "reflection frequency " << reflections / kN << " vs F " << F;
        }
    }
}

TEST(BsdfDelta, PlasticSpecularChoice) {
    Material m = makeMaterial(BsdfType::Plastic);
    m.specularReflectance = glm::vec3(0.8f);
    const double lum = [](glm::vec3 c) {
        return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    }(m.reflectance);
    const double w = 0.8 / (0.8 + lum);
    const std::vector<double> thetas = {0, 45, 80, 89};
    const double alpha = sidak(int(thetas.size()));
    constexpr uint32_t kN = 1u << 18;
    uint32_t seed = 3;
    for (double theta : thetas) {
        SCOPED_TRACE(theta);
        const glm::vec3 wo = woAt(theta);
        const double Fi = scene::fresnelDielectric(wo.z, m.eta);
        const double pSpec = Fi * w / (Fi * w + (1.0 - Fi) * (1.0 - w));
        const auto b = sampleBsdf(m, wo, kN, kRadiance, ++seed);
        double specular = 0.0;
        for (size_t i = 0; i < b.samples.size(); ++i) {
            if (!(b.flags(i) & kDelta)) {
                ASSERT_EQ(b.flags(i), kReflection | kDiffuse);
                continue;
            }
            specular += 1.0;
            ASSERT_EQ(b.flags(i), kReflection | kDelta);
            ASSERT_NEAR(b.samples[i].x, -wo.x, 1e-6);
            ASSERT_NEAR(b.samples[i].y, -wo.y, 1e-6);
            ASSERT_NEAR(b.samples[i].z, wo.z, 1e-6);
            ASSERT_NEAR(b.samples[i].w, pSpec, 1e-5);
            for (int k = 0; k < 3; ++k)
                ASSERT_NEAR(b.values[i][k] / b.samples[i].w, 0.8 * Fi / pSpec, 1e-4);
        }
        const double p = binomialPValue(specular, kN, pSpec);
        std::printf("[delta] plastic theta=%4.1f P_spec=%.5f freq=%.5f p=%.4f\n", theta, pSpec,
                    specular / kN, p);
        EXPECT_GE(p, alpha);
    }
}

TEST(BsdfDelta, NullPassesThrough) {
    const Material m = makeMaterial(BsdfType::Null);
    for (double theta : {20.0, 100.0}) {
        const glm::vec3 wo = woAt(theta);
        const auto b = sampleBsdf(m, wo, 64, kRadiance);
        for (size_t i = 0; i < b.samples.size(); ++i) {
            EXPECT_EQ(b.flags(i), kTransmission | kDelta | kNull);
            EXPECT_EQ(glm::vec3(b.samples[i]), -wo);
            EXPECT_EQ(b.samples[i].w, 1.0f);
            EXPECT_EQ(glm::vec3(b.values[i]), glm::vec3(1.0f));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Fresnel and microfacet terms.

TEST(Fresnel, MatchesCpuReference) {
    std::vector<glm::vec4> params;
    for (double eta : {1.5, 1.333, 2.4, 1.0 / 1.5})
        for (int i = 0; i <= 400; ++i)
            params.emplace_back(float(-1.0 + i / 200.0), float(eta), 0.2f, 3.0f);
    Gpu& g = Gpu::get();
    const auto& pipe = g.pipeline("fresnel_eval.comp");
    auto in = g.upload(params, "params");
    auto out = g.output(params.size(), "results");
    gpu::Bindings b;
    b.set("ParamBuffer", in).set("ResultBuffer", out);
    gpu::PushConstants pc(pipe);
    pc.set("count", uint32_t(params.size()));
    g.run(pipe, b, pc, uint32_t(params.size()));
    const auto r = g.download(*out, params.size());
    for (size_t i = 0; i < params.size(); ++i) {
        const double cosI = params[i].x, eta = params[i].y;
        SCOPED_TRACE(::testing::Message() << "cos " << cosI << " eta " << eta);
        EXPECT_NEAR(r[i].x, scene::fresnelDielectric(cosI, eta), 2e-6);
        // Snell: sin_t = sin_i / eta (inverted from inside); cos_t opposite in sign, 0 in TIR.
        const double e = cosI >= 0.0 ? eta : 1.0 / eta;
        const double sin2T = (1.0 - cosI * cosI) / (e * e);
        const double cosT = sin2T >= 1.0 ? 0.0 : (cosI >= 0.0 ? -1.0 : 1.0) * std::sqrt(1 - sin2T);
        EXPECT_NEAR(r[i].y, cosT, 1e-5);
        if (sin2T >= 1.0) {
            EXPECT_EQ(r[i].x, 1.0f) << "total internal reflection";
        }
        EXPECT_NEAR(r[i].z, fresnelConductorReference(std::abs(cosI), 0.2, 3.0), 1e-5);
    }
    // Normal incidence: ((eta - 1) / (eta + 1))^2.
    EXPECT_NEAR(scene::fresnelDielectric(1.0, 1.5), 0.04, 1e-12);
}

TEST(Fresnel, DiffuseReflectanceIdentity) {
    // Energy balance across a smooth interface: 1 - Fdr(1/eta) = (1 - Fdr(eta)) / eta^2.
    for (double eta : {1.1, 1.33, 1.5, 2.0}) {
        const double ext = scene::fresnelDiffuseReflectance(eta);
        const double in = scene::fresnelDiffuseReflectance(1.0 / eta);
        EXPECT_NEAR(1.0 - in, (1.0 - ext) / (eta * eta), 1e-7) << eta;
    }
    // Known value for glass (e.g. d'Eon & Irving 2011): Fdr(1.5) ~ 0.0918.
    EXPECT_NEAR(scene::fresnelDiffuseReflectance(1.5), 0.0918, 5e-4);
}

// Microfacet normalisation (Heitz 2014): projected area integral D(m) m.z dm = 1, and the
// visible normal density G1(wo) <wo.m> D(m) / wo.z integrates to 1 for every wo, which holds
// only if Lambda matches D. Quadrature in (theta, phi) with 2-point Gauss-Legendre cells.
TEST(Microfacet, NormalisationAndVisibleNormals) {
    const int nTheta = 1024, nPhi = 128;
    const double gl[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
    std::vector<glm::vec4> normals;
    std::vector<double> weights;
    const double dt = 0.5 * kPi / (nTheta / 2), dp = 2.0 * kPi / (nPhi / 2);
    for (int i = 0; i < nTheta; ++i) {
        const double theta = dt * (i / 2 + gl[i % 2]);
        for (int j = 0; j < nPhi; ++j) {
            const double phi = dp * (j / 2 + gl[j % 2]);
            normals.emplace_back(sphericalDirection(std::cos(theta), phi), 0.0f);
            weights.push_back(0.25 * dt * dp * std::sin(theta));
        }
    }
    Gpu& g = Gpu::get();
    const auto& pipe = g.pipeline("microfacet_eval.comp");
    auto nBuf = g.upload(normals, "normals");
    auto out = g.output(normals.size(), "results");
    for (uint32_t dist : {0u, 1u}) {
        for (float alpha : {0.1f, 0.5f, 1.0f}) {
            for (double theta : {0.0, 45.0, 80.0}) {
                SCOPED_TRACE(::testing::Message()
                             << "dist " << dist << " alpha " << alpha << " theta " << theta);
                const glm::vec3 wo = woAt(theta);
                auto woBuf = g.upload(std::vector<glm::vec4>{glm::vec4(wo, 0.0f)}, "wo");
                gpu::Bindings b;
                b.set("WoBuffer", woBuf).set("NormalBuffer", nBuf).set("ResultBuffer", out);
                gpu::PushConstants pc(pipe);
                pc.set("count", uint32_t(normals.size()))
                    .set("woCount", 1u)
                    .set("dist", dist)
                    .set("alpha", alpha);
                g.run(pipe, b, pc, uint32_t(normals.size()));
                const auto r = g.download(*out, normals.size());
                double area = 0.0, visible = 0.0, pdf = 0.0;
                for (size_t i = 0; i < normals.size(); ++i) {
                    const glm::vec3 m(normals[i]);
                    area += r[i].x * m.z * weights[i];
                    visible += r[i].y * std::max(0.0f, glm::dot(wo, m)) * r[i].x * weights[i];
                    pdf += r[i].z * weights[i];
                }
                EXPECT_NEAR(area, 1.0, 1e-3);
                EXPECT_NEAR(visible / wo.z, 1.0, 2e-3);
                // GGX samples visible normals (integral 1); Beckmann samples D cos (also 1).
                EXPECT_NEAR(pdf, 1.0, 2e-3);
            }
        }
    }
}

// Normals drawn by microfacet_sample_normals (rough manifold walks' offset normals) have density
// D(m) cos(theta_m): weighted by 1 / (D cos), the indicator of a cone of directions averages to
// the cone's solid angle 2 pi (1 - cos(half angle)) (D itself is checked above). One cone on the
// axis, and one tilted off it, which also sees the azimuth's distribution. 1M independent
// samples, within 4 standard errors (measured: 0.05-0.6 % of the solid angle).
TEST(Microfacet, SampledNormalsHaveDensityDCos) {
    Gpu& g = Gpu::get();
    const auto& pipe = g.pipeline("microfacet_sample_normals.comp");
    const uint32_t n = 1u << 20;
    auto out = g.output(n, "results");
    for (uint32_t dist : {0u, 1u}) {
        for (float alpha : {0.05f, 0.2f, 0.6f}) {
            SCOPED_TRACE(::testing::Message() << "dist " << dist << " alpha " << alpha);
            gpu::Bindings b;
            b.set("ResultBuffer", out);
            gpu::PushConstants pc(pipe);
            pc.set("count", n).set("dist", dist).set("alpha", alpha);
            g.run(pipe, b, pc, n);
            const auto r = g.download(*out, n);
            // Half angles atan(1.5 alpha) about the axis and atan(alpha) about a direction
            // tilted by atan(alpha) at azimuth 0.7.
            const double t = std::atan(double(alpha)), c0 = std::cos(std::atan(1.5 * alpha));
            const glm::dvec3 axis(std::sin(t) * std::cos(0.7), std::sin(t) * std::sin(0.7),
                                  std::cos(t));
            const double expect[2] = {2 * kPi * (1 - c0), 2 * kPi * (1 - std::cos(t))};
            double sum[2] = {0, 0}, sum2[2] = {0, 0};
            for (const glm::vec4& v : r) {
                const glm::dvec3 m(v);
                const double w = 1.0 / (double(v.w) * m.z);
                const bool in[2] = {m.z > c0, glm::dot(m, axis) > std::cos(t)};
                for (int k = 0; k < 2; ++k)
                    if (in[k]) {
                        sum[k] += w / expect[k];
                        sum2[k] += (w / expect[k]) * (w / expect[k]);
                    }
            }
            double ratio[2], se[2];
            for (int k = 0; k < 2; ++k) {
                ratio[k] = sum[k] / n;
                se[k] = std::sqrt((sum2[k] / n - ratio[k] * ratio[k]) / n);
                EXPECT_LT(std::abs(ratio[k] - 1.0), 4 * se[k])
                    << (k ? "tilted cone" : "cone on the axis");
            }
            std::printf(
                "dist %u alpha %.2f: cone on the axis %.5f +- %.5f, tilted %.5f +- %.5f of its "
                "solid angle\n",
                dist, alpha, ratio[0], se[0], ratio[1], se[1]);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Energy (white furnace: mean sample weight = directional albedo) and reciprocity.

glm::dvec3 meanWeight(const SampleBatch& b, double* stdError = nullptr) {
    glm::dvec3 sum(0.0), sum2(0.0);
    for (size_t i = 0; i < b.samples.size(); ++i) {
        if (!(b.samples[i].w > 0.0f)) continue;
        const glm::dvec3 w = glm::dvec3(glm::vec3(b.values[i])) / double(b.samples[i].w);
        sum += w;
        sum2 += w * w;
    }
    const double n = double(b.samples.size());
    const glm::dvec3 mean = sum / n;
    if (stdError) *stdError = std::sqrt(std::max(0.0, sum2.x / n - mean.x * mean.x) / n);
    return mean;
}

TEST(BsdfEnergy, LambertAlbedo) {
    Material m = makeMaterial(BsdfType::Diffuse);
    m.reflectance = glm::vec3(0.2f, 0.5f, 0.9f);
    m.twoSided = true;
    for (double theta : {0.0, 60.0, 150.0}) {
        const glm::dvec3 albedo = meanWeight(sampleBsdf(m, woAt(theta), 1u << 16, kRadiance));
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(albedo[k], m.reflectance[k], 1e-4) << theta;
    }
}

TEST(BsdfEnergy, RoughDielectricFurnace) {
    Material m = makeMaterial(BsdfType::RoughDielectric);
    m.specularReflectance = m.specularTransmittance = glm::vec3(1.0f);
    for (float alpha : {0.05f, 0.3f, 0.8f}) {
        m.alpha = alpha;
        for (double theta : {0.0, 45.0, 80.0, 160.0, 120.0}) {
            // Importance transport integrates the adjoint: albedo <= 1 on both sides.
            for (uint32_t mode : {kImportance, kRadiance}) {
                if (mode == kRadiance && theta > 90.0) continue;  // radiance gains eta^2 inside
                double se = 0.0;
                const double albedo = meanWeight(sampleBsdf(m, woAt(theta), 1u << 17, mode), &se).x;
                std::printf("[furnace] roughdielectric a=%.2f theta=%5.1f mode=%u albedo=%.5f\n",
                            alpha, theta, mode, albedo);
                EXPECT_LE(albedo, 1.0 + 4.0 * se) << "alpha " << alpha << " theta " << theta;
                // Single scattering loses energy at high roughness, but not most of it.
                if (mode == kImportance) {
                    EXPECT_GT(albedo, 0.5) << "alpha " << alpha << " theta " << theta;
                }
            }
        }
    }
    // Smooth limit: every importance-mode weight is exactly 1.
    Material smooth = makeMaterial(BsdfType::Dielectric);
    smooth.specularReflectance = smooth.specularTransmittance = glm::vec3(1.0f);
    for (double theta : {30.0, 150.0})
        EXPECT_NEAR(meanWeight(sampleBsdf(smooth, woAt(theta), 1u << 14, kImportance)).x, 1.0,
                    1e-5);
}

TEST(BsdfEnergy, PlasticWhiteFurnace) {
    // A white base under a clear smooth coat reflects everything: F_i + (1 - F_i) = 1 once the
    // internal-scattering term 1 / (1 - Fdr_int) is right.
    Material m = makeMaterial(BsdfType::Plastic);
    m.reflectance = glm::vec3(1.0f);
    m.specularReflectance = glm::vec3(1.0f);
    for (double theta : {0.0, 50.0, 85.0}) {
        double se = 0.0;
        const double albedo = meanWeight(sampleBsdf(m, woAt(theta), 1u << 18, kRadiance), &se).x;
        std::printf("[furnace] plastic theta=%4.1f albedo=%.5f +- %.5f\n", theta, albedo, se);
        EXPECT_NEAR(albedo, 1.0, 4.0 * se + 1e-4) << theta;
    }
}

// Random unit directions in the upper (sign > 0) or lower hemisphere.
std::vector<glm::vec4> randomDirections(size_t n, float sign, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<glm::vec4> d;
    while (d.size() < n) {
        const double z = 0.02 + 0.98 * u(rng);
        d.emplace_back(sphericalDirection(z, 2.0 * kPi * u(rng)) * glm::vec3(1, 1, sign), 0.0f);
    }
    return d;
}

// f(wo, wi) = f(wi, wo) for reflection: eval / |cos wi| is symmetric.
TEST(BsdfReciprocity, ReflectionLobes) {
    using scene::Microfacet;
    const std::vector<std::pair<std::string, Material>> materials = {
        {"diffuse", makeMaterial(BsdfType::Diffuse)},
        {"roughconductor ggx", makeMaterial(BsdfType::RoughConductor, 0.3f)},
        {"roughconductor beckmann",
         makeMaterial(BsdfType::RoughConductor, 0.3f, Microfacet::Beckmann)},
        {"plastic", makeMaterial(BsdfType::Plastic)},
        {"roughplastic", makeMaterial(BsdfType::RoughPlastic, 0.25f)},
        {"roughdielectric", makeMaterial(BsdfType::RoughDielectric, 0.3f)},
    };
    const auto a = randomDirections(4096, 1.0f, 11), b = randomDirections(4096, 1.0f, 12);
    for (const auto& [name, m] : materials) {
        SCOPED_TRACE(name);
        const auto fab = evalBsdf(m, a, b, kRadiance), fba = evalBsdf(m, b, a, kRadiance);
        int bad = 0;
        double maxErr = 0.0;
        for (size_t i = 0; i < a.size(); ++i) {
            for (int k = 0; k < 3; ++k) {
                const double x = fab[i][k] / b[i].z, y = fba[i][k] / a[i].z;
                const double err = std::abs(x - y) / std::max({std::abs(x), std::abs(y), 1e-6});
                maxErr = std::max(maxErr, err);
                if (err > 1e-4) ++bad;
            }
        }
        EXPECT_EQ(bad, 0) << "max relative asymmetry " << maxErr;
    }
}

// Refraction is not symmetric in radiance transport: f(wo, wi) eta_wi^2 = f(wi, wo) eta_wo^2
// (Veach 1997, Sec. 5.2); the importance mode is the adjoint f*(wo, wi) = f(wi, wo).
TEST(BsdfReciprocity, RefractionGeneralised) {
    Material m = makeMaterial(BsdfType::RoughDielectric, 0.4f);
    const auto above = randomDirections(4096, 1.0f, 21), below = randomDirections(4096, -1.0f, 22);
    const auto fOut = evalBsdf(m, above, below, kRadiance);  // wo outside (eta_wo = 1)
    const auto fIn = evalBsdf(m, below, above, kRadiance);   // wo inside (eta_wo = 1.5)
    const auto fInAdj = evalBsdf(m, below, above, kImportance);
    const double eta2 = double(m.eta) * m.eta;
    int bad = 0, nonzero = 0;
    for (size_t i = 0; i < above.size(); ++i) {
        const double x = fOut[i].x / std::abs(below[i].z) * eta2;
        const double y = fIn[i].x / std::abs(above[i].z);
        const double adj = fInAdj[i].x / std::abs(above[i].z);
        const double xr = fOut[i].x / std::abs(below[i].z);
        if (x > 0.0) ++nonzero;
        const double scale = std::max({std::abs(x), std::abs(y), 1e-2});
        // The two evaluations build the generalised half vector from opposite sides; its float
        // rounding reaches ~3e-4 relative in the tails of D, and more where wo.h -> 0 makes
        // 1 - F cancel (values < 1e-5, hence the absolute floor).
        if (std::abs(x - y) > 1e-3 * scale) ++bad;
        if (std::abs(xr - adj) > 1e-3 * std::max({xr, adj, 1e-2})) ++bad;
    }
    EXPECT_EQ(bad, 0);
    EXPECT_GT(nonzero, 500) << "too few refraction pairs with a non-zero BTDF";
}

// Opaque materials are black from below unless two-sided, where they mirror the front side.
TEST(BsdfFrames, TwoSidedMirrorsTheFront) {
    Material m = makeMaterial(BsdfType::RoughPlastic, 0.3f);
    const auto a = randomDirections(256, 1.0f, 31), b = randomDirections(256, 1.0f, 32);
    std::vector<glm::vec4> na = a, nb = b;
    for (auto& v : na) v.z = -v.z;
    for (auto& v : nb) v.z = -v.z;
    const auto front = evalBsdf(m, a, b, kRadiance);
    const auto backOneSided = evalBsdf(m, na, nb, kRadiance);
    m.twoSided = true;
    const auto backTwoSided = evalBsdf(m, na, nb, kRadiance);
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(backOneSided[i], glm::vec4(0.0f));
        EXPECT_EQ(backTwoSided[i], front[i]);
    }
}

}  // namespace
