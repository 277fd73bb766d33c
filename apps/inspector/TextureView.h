#pragma once
// How the texture viewer turns a float texture into display pixels: exposure, channel
// selection, false colour for signed and error images, pixel readout and saving. Pure CPU
// (the texture is read back anyway for the readout and for saving), so it is unit-tested.
#include <cstdint>
#include <string>
#include <vector>

#include "core/image/Image.h"

namespace loom::inspector {

enum class Channel { RGB, R, G, B, A, Luminance };
enum class ColorMode {
    Color,   // exposure, then sRGB encoding
    Signed,  // diverging blue (negative) - black - red (positive), scaled by range
    Error    // |value| through the perceptual false-colour ramp of core/image (log optional)
};
const char* channelName(Channel c);
const char* colorModeName(ColorMode m);

struct ViewSettings {
    float exposure = 0.0f;  // stops (Color)
    Channel channel = Channel::RGB;
    ColorMode mode = ColorMode::Color;
    float range = 1.0f;     // |value| mapped to full colour (Signed, Error)
    bool logScale = false;  // Error
};

// RGBA8, sRGB encoded, row-major top row first (what the display image holds).
std::vector<uint8_t> toDisplay(const ImageData& image, const ViewSettings& view);
// The selected channel(s) of one texel as display would see them, before mapping.
float channelValue(const ImageData& image, uint32_t x, uint32_t y, Channel channel);
// "(x, y) r g b a" for the texel under the cursor.
std::string pixelReadout(const ImageData& image, uint32_t x, uint32_t y);
// .exr/.hdr keep the raw floats; 8-bit formats (.png, .jpg) get the display mapping.
void saveView(const std::string& path, const ImageData& image, const ViewSettings& view);

}  // namespace loom::inspector
