#include "core/image/Image.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom {

namespace {

float halfToFloat(uint16_t h) {
    uint32_t sign = (h >> 15) & 1, exp = (h >> 10) & 0x1f, mant = h & 0x3ff;
    float v;
    if (exp == 0)
        v = std::ldexp(float(mant), -24);
    else if (exp == 31)
        v = mant ? NAN : INFINITY;
    else
        v = std::ldexp(float(mant | 0x400), int(exp) - 25);
    return sign ? -v : v;
}

uint16_t floatToHalf(float f) {
    uint32_t x;
    std::memcpy(&x, &f, 4);
    uint32_t sign = (x >> 16) & 0x8000;
    int exp = int((x >> 23) & 0xff) - 127 + 15;
    uint32_t mant = x & 0x7fffff;
    if (((x >> 23) & 0xff) == 0xff) return uint16_t(sign | 0x7c00 | (mant ? 0x200 : 0));
    if (exp >= 31) return uint16_t(sign | 0x7c00);
    if (exp <= 0) {
        if (exp < -10) return uint16_t(sign);
        mant |= 0x800000;
        uint32_t shift = uint32_t(14 - exp);
        uint32_t h = mant >> shift;
        if ((mant >> (shift - 1)) & 1) ++h;  // round half up
        return uint16_t(sign | h);
    }
    uint32_t h = sign | (uint32_t(exp) << 10) | (mant >> 13);
    if (mant & 0x1000) ++h;
    return uint16_t(h);
}

}  // namespace

ImageData downloadImage(gpu::Context& gpu, const gpu::Image& image) {
    using gpu::Format;
    uint32_t n = image.width() * image.height();
    std::vector<uint8_t> raw(image.byteSize());
    gpu.downloadImage(image, raw.data());
    ImageData out =
        ImageData::make(image.width(), image.height(), gpu::channelCount(image.format()));
    switch (image.format()) {
        case Format::RGBA32F:
        case Format::RG32F:
        case Format::R32F:
            std::memcpy(out.pixels.data(), raw.data(), raw.size());
            break;
        case Format::RGBA16F: {
            auto* h = reinterpret_cast<const uint16_t*>(raw.data());
            for (size_t i = 0; i < size_t(n) * 4; ++i) out.pixels[i] = halfToFloat(h[i]);
            break;
        }
        case Format::R32UI:
        case Format::RGBA32UI: {
            auto* u = reinterpret_cast<const uint32_t*>(raw.data());
            for (size_t i = 0; i < out.pixels.size(); ++i) out.pixels[i] = float(u[i]);
            break;
        }
        case Format::R32I: {
            auto* s = reinterpret_cast<const int32_t*>(raw.data());
            for (size_t i = 0; i < n; ++i) out.pixels[i] = float(s[i]);
            break;
        }
        case Format::RGBA8:
            for (size_t i = 0; i < size_t(n) * 4; ++i) out.pixels[i] = raw[i] / 255.0f;
            break;
    }
    return out;
}

void uploadImage(gpu::Context& gpu, const gpu::Image& image, const ImageData& data) {
    using gpu::Format;
    if (data.width != image.width() || data.height != image.height())
        throw UserError(fmt::format("upload: image is {}x{} but GPU image '{}' is {}x{}",
                                    data.width, data.height, image.name(), image.width(),
                                    image.height()));
    uint32_t dstC = gpu::channelCount(image.format());
    size_t n = size_t(image.width()) * image.height();
    // Expand/shrink channels: missing colour channels repeat the first, missing alpha is 1.
    auto value = [&](size_t p, uint32_t c) -> float {
        if (c < data.channels) return data.pixels[p * data.channels + c];
        if (c == 3) return 1.0f;
        return data.pixels[p * data.channels];
    };
    std::vector<uint8_t> raw(image.byteSize());
    for (size_t p = 0; p < n; ++p)
        for (uint32_t c = 0; c < dstC; ++c) {
            float v = value(p, c);
            switch (image.format()) {
                case Format::RGBA16F:
                    reinterpret_cast<uint16_t*>(raw.data())[p * dstC + c] = floatToHalf(v);
                    break;
                case Format::R32UI:
                case Format::RGBA32UI:
                    reinterpret_cast<uint32_t*>(raw.data())[p * dstC + c] =
                        uint32_t(std::max(0.0f, v));
                    break;
                case Format::R32I:
                    reinterpret_cast<int32_t*>(raw.data())[p] = int32_t(v);
                    break;
                case Format::RGBA8:
                    raw[p * 4 + c] = uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
                    break;
                default:
                    reinterpret_cast<float*>(raw.data())[p * dstC + c] = v;
                    break;
            }
        }
    gpu.uploadImage(image, raw.data());
}

const char* metricName(Metric m) {
    switch (m) {
        case Metric::MSE:
            return "mse";
        case Metric::RelMSE:
            return "relmse";
        case Metric::RMSE:
            return "rmse";
        case Metric::MAPE:
            return "mape";
    }
    return "?";
}

Metric parseMetric(const std::string& name) {
    for (Metric m : {Metric::MSE, Metric::RelMSE, Metric::RMSE, Metric::MAPE})
        if (name == metricName(m)) return m;
    throw UserError("unknown metric '" + name + "'; valid: mse, relmse, rmse, mape");
}

double pixelError(Metric m, const float* x, const float* r, uint32_t channels, double eps) {
    uint32_t n = std::min(channels, 3u);
    double sum = 0.0;
    for (uint32_t c = 0; c < n; ++c) {
        double d = double(x[c]) - double(r[c]);
        switch (m) {
            case Metric::MSE:
            case Metric::RMSE:
                sum += d * d;
                break;
            case Metric::RelMSE:
                sum += d * d / (double(r[c]) * r[c] + eps);
                break;
            case Metric::MAPE:
                sum += std::abs(d) / (std::abs(double(r[c])) + eps);
                break;
        }
    }
    return sum / n;
}

double computeMetric(Metric m, const ImageData& image, const ImageData& reference, double eps) {
    if (image.width != reference.width || image.height != reference.height)
        throw UserError(fmt::format("metric: image is {}x{} but reference is {}x{}", image.width,
                                    image.height, reference.width, reference.height));
    uint32_t ch = std::min(image.channels, reference.channels);
    double sum = 0.0;
    size_t n = size_t(image.width) * image.height;
    std::vector<float> a(4), b(4);
    for (size_t p = 0; p < n; ++p) {
        for (uint32_t c = 0; c < ch; ++c) {
            a[c] = image.pixels[p * image.channels + c];
            b[c] = reference.pixels[p * reference.channels + c];
        }
        sum += pixelError(m, a.data(), b.data(), ch, eps);
    }
    double mean = sum / double(n);
    return m == Metric::RMSE ? std::sqrt(mean) : mean;
}

ImageData falseColor(const ImageData& values, float maxValue, bool logScale) {
    ImageData out = ImageData::make(values.width, values.height, 4, 1.0f);
    for (size_t p = 0; p < size_t(values.width) * values.height; ++p) {
        float v = values.pixels[p * values.channels];
        float t = logScale ? std::log10(1.0f + 9.0f * std::max(v, 0.0f) / maxValue)
                           : std::max(v, 0.0f) / maxValue;
        t = std::clamp(t, 0.0f, 1.0f);
        // Same ramp as shaders/lib/colormap.glsl (dark blue -> cyan -> yellow -> red).
        float r = std::clamp(1.5f - std::abs(4.0f * t - 3.0f), 0.0f, 1.0f);
        float g = std::clamp(1.5f - std::abs(4.0f * t - 2.0f), 0.0f, 1.0f);
        float b = std::clamp(1.5f - std::abs(4.0f * t - 1.0f), 0.0f, 1.0f);
        out.pixels[p * 4 + 0] = r;
        out.pixels[p * 4 + 1] = g;
        out.pixels[p * 4 + 2] = b;
    }
    return out;
}

}  // namespace loom
