// Inspector texture viewer: display mapping (exposure, channels, false colour), pixel readout
// and saving. No window, no GPU.
#include <gtest/gtest.h>

#include "apps/inspector/TextureView.h"
#include "tests/support/TestSupport.h"

namespace {

using loom::ImageData;
using namespace loom::inspector;

ImageData pixels(std::initializer_list<std::array<float, 4>> texels) {
    ImageData img = ImageData::make(uint32_t(texels.size()), 1, 4);
    size_t i = 0;
    for (const auto& t : texels)
        for (float v : t) img.pixels[i++] = v;
    return img;
}

TEST(InspectorTextureView, ExposureAndSrgb) {
    ImageData img = pixels({{0.0f, 0.5f, 1.0f, 1.0f}, {0.25f, 0.25f, 0.25f, 1.0f}});
    ViewSettings v;
    auto d = toDisplay(img, v);
    ASSERT_EQ(d.size(), 8u);
    EXPECT_EQ(d[0], 0);
    EXPECT_EQ(d[1], 188);  // sRGB(0.5)
    EXPECT_EQ(d[2], 255);
    EXPECT_EQ(d[3], 255);
    v.exposure = 1.0f;  // 0.25 * 2 = 0.5
    d = toDisplay(img, v);
    EXPECT_EQ(d[4], 188);
}

TEST(InspectorTextureView, ChannelSelect) {
    ImageData img = pixels({{0.0f, 1.0f, 0.0f, 0.5f}});
    ViewSettings v;
    v.channel = Channel::G;
    auto d = toDisplay(img, v);
    EXPECT_EQ(d[0], 255);
    EXPECT_EQ(d[1], 255);
    EXPECT_EQ(d[2], 255);
    v.channel = Channel::R;
    EXPECT_EQ(toDisplay(img, v)[1], 0);
    EXPECT_FLOAT_EQ(channelValue(img, 0, 0, Channel::A), 0.5f);
    EXPECT_NEAR(channelValue(img, 0, 0, Channel::Luminance), 0.7152f, 1e-6);
    // Single-channel textures show as grey; alpha reads as 1.
    ImageData mono = ImageData::make(1, 1, 1, 0.25f);
    EXPECT_FLOAT_EQ(channelValue(mono, 0, 0, Channel::G), 0.25f);
    EXPECT_FLOAT_EQ(channelValue(mono, 0, 0, Channel::A), 1.0f);
}

TEST(InspectorTextureView, SignedAndErrorFalseColour) {
    ImageData img =
        pixels({{-1.0f, 0.0f, 0.0f, 1.0f}, {1.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f, 1.0f}});
    ViewSettings v;
    v.channel = Channel::R;
    v.mode = ColorMode::Signed;
    auto d = toDisplay(img, v);
    EXPECT_GT(d[2], 200);  // negative: blue
    EXPECT_EQ(d[0], 0);
    EXPECT_GT(d[4], 200);  // positive: red
    EXPECT_EQ(d[6], 0);
    EXPECT_EQ(d[8] + d[9] + d[10], 0);  // zero: black
    v.mode = ColorMode::Error;
    d = toDisplay(img, v);
    // |-1| and |1| map to the same hot colour, 0 to the cold end; colours differ.
    EXPECT_EQ(d[0], d[4]);
    EXPECT_NE(d[0] * 65536 + d[1] * 256 + d[2], d[8] * 65536 + d[9] * 256 + d[10]);
}

TEST(InspectorTextureView, ReadoutAndSave) {
    ImageData img = pixels({{0.125f, 2.0f, -3.0f, 1.0f}});
    EXPECT_EQ(pixelReadout(img, 0, 0), "(0, 0) 0.125 2 -3 1");
    EXPECT_EQ(pixelReadout(img, 1, 0), "");
    loom::test::TempDir dir("loom-inspector");
    saveView(dir / "t.exr", img, {});
    ImageData back = loom::readImage(dir / "t.exr");
    EXPECT_FLOAT_EQ(back.at(0, 0, 1), 2.0f);  // raw floats
    saveView(dir / "t.png", img, {});
    ImageData png = loom::readImage(dir / "t.png");
    EXPECT_NEAR(png.at(0, 0, 1), 1.0f, 1e-6);  // display mapping: clamped
    EXPECT_NEAR(png.at(0, 0, 2), 0.0f, 1e-6);
}

}  // namespace
