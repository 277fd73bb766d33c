#include "apps/inspector/TextureView.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

namespace loom::inspector {

const char* channelName(Channel c) {
    switch (c) {
        case Channel::RGB:
            return "RGB";
        case Channel::R:
            return "R";
        case Channel::G:
            return "G";
        case Channel::B:
            return "B";
        case Channel::A:
            return "A";
        case Channel::Luminance:
            return "Luminance";
    }
    return "?";
}

const char* colorModeName(ColorMode m) {
    switch (m) {
        case ColorMode::Color:
            return "Colour";
        case ColorMode::Signed:
            return "Signed (false colour)";
        case ColorMode::Error:
            return "Error (false colour)";
    }
    return "?";
}

namespace {

float srgbEncode(float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

uint8_t toByte(float v) {
    return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
}

// The texel's channel c, or what a missing channel reads as (0, alpha 1).
float texel(const ImageData& img, uint32_t x, uint32_t y, uint32_t c) {
    if (c < img.channels) return img.at(x, y, c);
    return c == 3 ? 1.0f : (img.channels == 1 && c < 3 ? img.at(x, y, 0) : 0.0f);
}

}  // namespace

float channelValue(const ImageData& img, uint32_t x, uint32_t y, Channel channel) {
    switch (channel) {
        case Channel::R:
            return texel(img, x, y, 0);
        case Channel::G:
            return texel(img, x, y, 1);
        case Channel::B:
            return texel(img, x, y, 2);
        case Channel::A:
            return texel(img, x, y, 3);
        case Channel::RGB:
        case Channel::Luminance:
            // Rec. 709 luminance; a signed/error view of RGB uses it too.
            return 0.2126f * texel(img, x, y, 0) + 0.7152f * texel(img, x, y, 1) +
                   0.0722f * texel(img, x, y, 2);
    }
    return 0.0f;
}

std::vector<uint8_t> toDisplay(const ImageData& img, const ViewSettings& view) {
    const size_t n = size_t(img.width) * img.height;
    std::vector<uint8_t> out(n * 4, 255);
    const float scale = std::exp2(view.exposure);
    const float range = view.range > 0.0f ? view.range : 1.0f;
    ImageData ramp;
    if (view.mode == ColorMode::Error) {
        ImageData values = ImageData::make(img.width, img.height, 1);
        for (uint32_t y = 0; y < img.height; ++y)
            for (uint32_t x = 0; x < img.width; ++x)
                values.at(x, y, 0) = std::abs(channelValue(img, x, y, view.channel));
        ramp = falseColor(values, range, view.logScale);
    }
    for (uint32_t y = 0; y < img.height; ++y)
        for (uint32_t x = 0; x < img.width; ++x) {
            uint8_t* o = &out[(size_t(y) * img.width + x) * 4];
            float rgb[3];
            if (view.mode == ColorMode::Color) {
                if (view.channel == Channel::RGB) {
                    for (uint32_t c = 0; c < 3; ++c) rgb[c] = texel(img, x, y, c) * scale;
                } else {
                    rgb[0] = rgb[1] = rgb[2] = channelValue(img, x, y, view.channel) * scale;
                }
                for (int c = 0; c < 3; ++c) o[c] = toByte(srgbEncode(rgb[c]));
            } else if (view.mode == ColorMode::Signed) {
                float v = channelValue(img, x, y, view.channel) / range;
                float a = std::min(std::abs(v), 1.0f);
                if (!std::isfinite(v)) {  // NaN/Inf stand out in magenta
                    o[0] = 255, o[1] = 0, o[2] = 255;
                } else {
                    o[0] = toByte(srgbEncode(v > 0 ? a : 0.0f));
                    o[1] = toByte(srgbEncode(0.15f * a));
                    o[2] = toByte(srgbEncode(v < 0 ? a : 0.0f));
                }
            } else {
                // falseColor() returns display-ready colours.
                for (uint32_t c = 0; c < 3; ++c)
                    o[c] = toByte(ramp.at(x, y, std::min(c, ramp.channels - 1)));
            }
        }
    return out;
}

std::string pixelReadout(const ImageData& img, uint32_t x, uint32_t y) {
    if (x >= img.width || y >= img.height) return "";
    std::string s = fmt::format("({}, {})", x, y);
    for (uint32_t c = 0; c < img.channels; ++c) s += fmt::format(" {:.5g}", img.at(x, y, c));
    return s;
}

void saveView(const std::string& path, const ImageData& img, const ViewSettings& view) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".exr" || ext == ".hdr" || ext == ".pfm") {
        writeImage(path, img);
        return;
    }
    // 8-bit: what the viewer shows; writeImage() stores 0..1 values as they are.
    auto bytes = toDisplay(img, view);
    ImageData shown = ImageData::make(img.width, img.height, 4);
    for (size_t i = 0; i < bytes.size(); ++i) shown.pixels[i] = float(bytes[i]) / 255.0f;
    writeImage(path, shown);
}

}  // namespace loom::inspector
