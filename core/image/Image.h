#pragma once
// CPU images (float, interleaved channels), image files (ImageFile.cpp), error metrics and
// false colour. Used by the CLI, Lua, tests and the inspector.
#include <cstdint>
#include <string>
#include <vector>

#include "core/gpu/Context.h"

namespace loom {

struct ImageData {
    uint32_t width = 0, height = 0, channels = 4;
    std::vector<float> pixels;  // row-major, top row first
    float& at(uint32_t x, uint32_t y, uint32_t c) {
        return pixels[(size_t(y) * width + x) * channels + c];
    }
    float at(uint32_t x, uint32_t y, uint32_t c) const {
        return pixels[(size_t(y) * width + x) * channels + c];
    }
    static ImageData make(uint32_t w, uint32_t h, uint32_t c, float fill = 0.0f) {
        return {w, h, c, std::vector<float>(size_t(w) * h * c, fill)};
    }
};

// Reads EXR, PFM, Radiance HDR, PNG (8 and 16 bit), JPEG, TGA, BMP and PNM, chosen by the
// file's magic bytes (Mitsuba 3's set). Integer files are returned as stored (0..1); pass
// linearize=true to decode sRGB to linear (alpha stays as stored). EXR channels come as R, G,
// B, A (or Y, A), then the others by name. Throws UserError naming the file.
ImageData readImage(const std::string& path, bool linearize = false);
// Reads only the header; throws UserError when the file cannot be opened as an image.
void readImageSize(const std::string& path, uint32_t& width, uint32_t& height);
// Writes by extension: .exr (32-bit float, ZIP), .pfm and .hdr store values as they are;
// .png, .jpg, .tga, .bmp and .ppm clamp to [0,1] and quantise to 8 bits (apply ToneMap first
// for HDR data). Formats without alpha (hdr, jpg, pfm, ppm) drop the fourth channel.
// Throws UserError when writeImage(path, ...) would fail for the path alone: no extension, no
// writer for it, or a directory that cannot be written. Checked before a render starts.
void checkImagePath(const std::string& path);
void writeImage(const std::string& path, const ImageData& image);

// GPU <-> CPU: converts from/to the image's texel format.
ImageData downloadImage(gpu::Context& gpu, const gpu::Image& image);
void uploadImage(gpu::Context& gpu, const gpu::Image& image, const ImageData& data);

// Error metrics over the first three channels (RGB; one channel for single-channel images).
// relMSE = mean((x-r)^2 / (r^2 + eps)), MAPE = mean(|x-r| / (|r| + eps)).
enum class Metric { MSE, RelMSE, RMSE, MAPE };
const char* metricName(Metric m);
Metric parseMetric(const std::string& name);  // throws UserError
double computeMetric(Metric m, const ImageData& image, const ImageData& reference,
                     double eps = 1e-2);
// Per-pixel error value for a metric (before averaging), shared by the CPU metric, the
// ErrorMetric pass's tests and false colour.
double pixelError(Metric m, const float* x, const float* r, uint32_t channels, double eps);
// Maps values in [0, maxValue] (log scale when logScale) to a perceptual colour ramp.
ImageData falseColor(const ImageData& values, float maxValue, bool logScale);

}  // namespace loom
