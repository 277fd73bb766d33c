#include "core/scene/EnvMapDistribution.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <string>

#include "core/gpu/Context.h"

namespace loom::scene {

namespace {

// Normalises f into a density over [0,1] (n equal bins) and its CDF (n + 1 entries). A zero
// function becomes uniform so a row/map without energy still has a valid (never used) CDF.
double buildPiecewise(const double* f, size_t n, float* pdf, float* cdf) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += f[i];
    const double integral = sum / double(n);
    double acc = 0.0;
    cdf[0] = 0.0f;
    for (size_t i = 0; i < n; ++i) {
        const double p = integral > 0.0 ? f[i] / integral : 1.0;
        pdf[i] = float(p);
        acc += p / double(n);
        cdf[i + 1] = float(acc);
    }
    cdf[n] = 1.0f;  // exact end point: the binary search never runs past the last bin
    return integral;
}

const float* checkedTexels(const Texture& texture) {
    if (texture.width == 0 || texture.height == 0 ||
        texture.rgba.size() < size_t(texture.width) * texture.height * 4)
        throw std::invalid_argument("environment map '" + texture.name + "' (" + texture.path +
                                    ") needs width x height RGBA texels (a loaded bitmap)");
    return texture.rgba.data();
}

// Rotation part of a transform, Gram-Schmidt orthonormalised (scale and shear dropped).
glm::mat3 rotationOf(const glm::mat4& m) {
    glm::vec3 x = glm::normalize(glm::vec3(m[0]));
    glm::vec3 y = glm::vec3(m[1]) - glm::dot(glm::vec3(m[1]), x) * x;
    y = glm::normalize(y);
    glm::vec3 z = glm::cross(x, y);
    if (glm::dot(z, glm::vec3(m[2])) < 0.0f) z = -z;  // keep the handedness of the input
    return glm::mat3(x, y, z);
}

float bitsFloat(uint32_t u) {
    float f;
    std::memcpy(&f, &u, sizeof(f));
    return f;
}

}  // namespace

EnvMapDistribution::EnvMapDistribution(const Texture& texture, const glm::mat4& toWorld)
    : EnvMapDistribution(checkedTexels(texture), texture.width, texture.height, toWorld) {}

EnvMapDistribution::EnvMapDistribution(const float* rgba, uint32_t width, uint32_t height,
                                       const glm::mat4& toWorld)
    : mWidth(width), mHeight(height), mToWorld(rotationOf(toWorld)) {
    if (width == 0 || height == 0 || rgba == nullptr)
        throw std::invalid_argument("environment map distribution needs a non-empty image");
    const size_t W = width, H = height;
    // f(u, v) = luminance x sin(theta) at the texel centre: sin(theta) is the lat-long
    // Jacobian dw = 2 pi^2 sin(theta) du dv, so samples follow the radiance in solid angle.
    std::vector<double> f(W * H);
    mRadiance.resize(3 * W * H);
    double power = 0.0;  // integral of Y dw
    for (size_t j = 0; j < H; ++j) {
        const double sinTheta = std::sin(std::numbers::pi * (double(j) + 0.5) / double(H));
        const double texelSolidAngle = 2.0 * std::numbers::pi / double(W) *
                                       (std::cos(std::numbers::pi * double(j) / double(H)) -
                                        std::cos(std::numbers::pi * double(j + 1) / double(H)));
        for (size_t i = 0; i < W; ++i) {
            const float* t = rgba + 4 * (j * W + i);
            for (int c = 0; c < 3; ++c) mRadiance[3 * (j * W + i) + c] = t[c];
            double lum = 0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2];
            lum = std::isfinite(lum) ? std::max(lum, 0.0) : 0.0;
            f[j * W + i] = lum * sinTheta;
            power += lum * texelSolidAngle;
        }
    }
    mAverageLuminance = power / (4.0 * std::numbers::pi);
    const size_t margPdf = 0, margCdf = H, condPdf = 2 * H + 1, condCdf = condPdf + H * W;
    mDistribution.assign(condCdf + H * (W + 1), 0.0f);
    // Conditional densities p(u | v) per row, then the marginal p(v) of the row integrals.
    std::vector<double> rows(H);
    for (size_t j = 0; j < H; ++j)
        rows[j] = buildPiecewise(&f[j * W], W, &mDistribution[condPdf + j * W],
                                 &mDistribution[condCdf + j * (W + 1)]);
    buildPiecewise(rows.data(), H, &mDistribution[margPdf], &mDistribution[margCdf]);
    mJoint.resize(W * H);
    for (size_t j = 0; j < H; ++j)
        for (size_t i = 0; i < W; ++i)
            mJoint[j * W + i] =
                double(mDistribution[margPdf + j]) * double(mDistribution[condPdf + j * W + i]);
}

double EnvMapDistribution::pdfUv(glm::dvec2 uv) const {
    const size_t i = std::min(size_t(std::max(uv.x, 0.0) * mWidth), size_t(mWidth - 1));
    const size_t j = std::min(size_t(std::max(uv.y, 0.0) * mHeight), size_t(mHeight - 1));
    return mJoint[j * mWidth + i];
}

double EnvMapDistribution::pdfDirection(glm::dvec3 local) const {
    const double sinTheta = std::sqrt(local.x * local.x + local.z * local.z);
    return sinTheta > 0.0
               ? pdfUv(uv(local)) / (2.0 * std::numbers::pi * std::numbers::pi * sinTheta)
               : 0.0;
}

glm::dvec3 EnvMapDistribution::direction(glm::dvec2 uv) {
    const double phi = 2.0 * std::numbers::pi * uv.x, theta = std::numbers::pi * uv.y;
    return {std::sin(phi) * std::sin(theta), std::cos(theta), -std::cos(phi) * std::sin(theta)};
}

glm::dvec2 EnvMapDistribution::uv(glm::dvec3 d) {
    double u = (d.x == 0.0 && d.z == 0.0) ? 0.0 : std::atan2(d.x, -d.z) / (2.0 * std::numbers::pi);
    if (u < 0.0) u += 1.0;
    return {u >= 1.0 ? 0.0 : u, std::acos(std::clamp(d.y, -1.0, 1.0)) / std::numbers::pi};
}

std::vector<float> packEnvMapData(const std::vector<EnvMapDistribution>& maps) {
    std::vector<float> data(1 + maps.size(), 0.0f);
    data[0] = bitsFloat(uint32_t(maps.size()));
    for (size_t k = 0; k < maps.size(); ++k) {
        const EnvMapDistribution& m = maps[k];
        // Records start on a 4-float boundary (vec4-friendly reads).
        data.resize((data.size() + 3) / 4 * 4, 0.0f);
        const size_t base = data.size();
        data[1 + k] = bitsFloat(uint32_t(base));
        constexpr uint32_t kRadianceOffset = 32;
        const uint32_t distOffset = kRadianceOffset + uint32_t(m.radiance().size());
        data.resize(base + distOffset + m.distribution().size(), 0.0f);
        data[base + 0] = bitsFloat(m.width());
        data[base + 1] = bitsFloat(m.height());
        data[base + 2] = bitsFloat(kRadianceOffset);
        data[base + 3] = bitsFloat(distOffset);
        const glm::mat3 toLocal = glm::transpose(m.toWorld());
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) {
                data[base + 4 + 4 * c + r] = m.toWorld()[c][r];
                data[base + 16 + 4 * c + r] = toLocal[c][r];
            }
        std::copy(m.radiance().begin(), m.radiance().end(), data.begin() + base + kRadianceOffset);
        std::copy(m.distribution().begin(), m.distribution().end(),
                  data.begin() + base + distOffset);
    }
    return data;
}

std::shared_ptr<gpu::Buffer> packEnvMaps(gpu::Context& gpu,
                                         const std::vector<EnvMapDistribution>& maps) {
    const std::vector<float> data = packEnvMapData(maps);
    auto buffer = gpu.createBuffer(data.size() * sizeof(float), "SceneEnvMaps");
    gpu.uploadBuffer(*buffer, data.data(), data.size() * sizeof(float));
    return buffer;
}

void bindEnvMaps(gpu::Bindings& bindings, const std::shared_ptr<gpu::Buffer>& buffer) {
    bindings.set("SceneEnvMaps", buffer);
}

}  // namespace loom::scene
