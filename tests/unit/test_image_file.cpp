// Image files (core/image/ImageFile.cpp): every writable format round-trips within what the
// format stores, files made by other means (OpenEXR directly, hand-encoded PNG and PFM) read
// as their bytes say, and malformed files are UserErrors naming the file.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>
#include <stb_image.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/image/Image.h"
#include "core/util/Error.h"

using namespace loom;
namespace fs = std::filesystem;

namespace {

fs::path tmpDir() {
    fs::path d = fs::temp_directory_path() / ("loom_image_file_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

// A smooth gradient with values above 1 in the first channel (HDR data).
ImageData gradient(uint32_t w, uint32_t h, uint32_t c, float scale = 1.0f) {
    ImageData img = ImageData::make(w, h, c);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            for (uint32_t k = 0; k < c; ++k)
                img.at(x, y, k) = scale * (float(x + 2 * y + 3 * k) / float(w + 2 * h + 3 * c));
    return img;
}

void writeBytes(const fs::path& p, const std::string& bytes) {
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

std::string errorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const UserError& e) {
        return e.what();
    }
    return "";
}

// PNG chunk: length, type, data, CRC-32 of type and data (PNG spec, section 5.3).
std::string pngChunk(const std::string& type, const std::string& data) {
    auto be32 = [](uint32_t v) {
        return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    };
    std::string td = type + data;
    uLong crc = crc32(0, reinterpret_cast<const Bytef*>(td.data()), uInt(td.size()));
    return be32(uint32_t(data.size())) + td + be32(uint32_t(crc));
}

// A 16-bit greyscale PNG, encoded here from the spec (zlib for the IDAT stream).
std::string png16Grey(uint32_t w, uint32_t h, const std::vector<uint16_t>& values) {
    auto be32 = [](uint32_t v) {
        return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    };
    std::string ihdr = be32(w) + be32(h) + std::string{16, 0, 0, 0, 0};  // 16-bit, grey
    std::string raw;
    for (uint32_t y = 0; y < h; ++y) {
        raw.push_back(0);  // filter type None
        for (uint32_t x = 0; x < w; ++x) {
            uint16_t v = values[y * w + x];
            raw.push_back(char(v >> 8));
            raw.push_back(char(v & 0xff));
        }
    }
    uLongf size = compressBound(uLong(raw.size()));
    std::string z(size, '\0');
    compress(reinterpret_cast<Bytef*>(z.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
             uLong(raw.size()));
    z.resize(size);
    return std::string("\x89PNG\r\n\x1a\n", 8) + pngChunk("IHDR", ihdr) + pngChunk("IDAT", z) +
           pngChunk("IEND", "");
}

}  // namespace

TEST(ImageFile, FloatFormatsRoundTrip) {
    fs::path d = tmpDir();
    for (uint32_t c : {1u, 2u, 3u, 4u}) {
        ImageData img = gradient(7, 5, c, 40.0f);
        img.at(3, 2, 0) = -1.5f;  // EXR and PFM keep negative values
        writeImage((d / "f.exr").string(), img);
        ImageData exr = readImage((d / "f.exr").string());
        ASSERT_EQ(exr.channels, c);
        EXPECT_TRUE(exr.pixels == img.pixels) << c << " channels";

        writeImage((d / "f.pfm").string(), img);
        ImageData pfm = readImage((d / "f.pfm").string());
        ASSERT_EQ(pfm.channels, c == 1 ? 1u : 3u);
        for (uint32_t y = 0; y < 5; ++y)
            for (uint32_t x = 0; x < 7; ++x)
                for (uint32_t k = 0; k < pfm.channels; ++k)
                    EXPECT_EQ(pfm.at(x, y, k), k < c ? img.at(x, y, k) : 0.0f);
    }
}

TEST(ImageFile, RadianceHdrKeepsEightBitsOfMantissa) {
    fs::path d = tmpDir();
    ImageData img = gradient(9, 4, 3, 100.0f);
    img.at(0, 0, 0) = img.at(0, 0, 1) = img.at(0, 0, 2) = 0.0f;
    writeImage((d / "f.hdr").string(), img);
    ImageData back = readImage((d / "f.hdr").string());
    ASSERT_EQ(back.channels, 3u);
    ASSERT_EQ(back.width, 9u);
    for (size_t p = 0; p < 36; ++p) {
        // RGBE shares one exponent: each channel is within 2^-8 of the pixel's largest one.
        float m = std::max({img.pixels[p * 3], img.pixels[p * 3 + 1], img.pixels[p * 3 + 2]});
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(back.pixels[p * 3 + k], img.pixels[p * 3 + k], m / 128.0f + 1e-6f);
    }
}

// Loom's RGBE reader against stb_image's decoder, bit for bit, on RLE (width >= 8) and flat
// (width < 8) scanlines.
TEST(ImageFile, RadianceHdrReadsAsStbImageDoes) {
    fs::path d = tmpDir();
    for (uint32_t w : {5u, 9u, 64u}) {
        std::string name = "w";  // not "w" + std::to_string(w): GCC 12's -Wrestrict false positive
        name += std::to_string(w) + ".hdr";
        fs::path p = d / name;
        writeImage(p.string(), gradient(w, 7, 3, 30.0f));
        std::ifstream in(p, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        int sw = 0, sh = 0, sn = 0;
        float* ref = stbi_loadf_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                                            int(bytes.size()), &sw, &sh, &sn, 3);
        ASSERT_NE(ref, nullptr);
        ImageData img = readImage(p.string());
        ASSERT_EQ(img.width, uint32_t(sw));
        ASSERT_EQ(img.height, uint32_t(sh));
        EXPECT_TRUE(img.pixels == std::vector<float>(ref, ref + size_t(sw) * sh * 3)) << w;
        stbi_image_free(ref);
    }
}

TEST(ImageFile, EightBitFormatsQuantiseAndClamp) {
    fs::path d = tmpDir();
    for (const char* ext : {".png", ".tga", ".bmp", ".ppm"}) {
        for (uint32_t c : {1u, 3u, 4u}) {
            if (std::string(ext) == ".ppm" && c == 4) continue;
            ImageData img = gradient(6, 3, c, 1.3f);  // some values above 1 clamp
            img.at(1, 1, 0) = NAN;                    // a NaN is written as 0
            fs::path p = d / (std::string("q") + ext);
            writeImage(p.string(), img);
            ImageData back = readImage(p.string());
            ASSERT_EQ(back.width, 6u) << ext;
            // BMP stores grey as RGB.
            const uint32_t stored = std::string(ext) == ".bmp" && c == 1 ? 3 : c;
            ASSERT_EQ(back.channels, stored) << ext << " " << c;
            for (size_t p = 0; p < size_t(6 * 3); ++p)
                for (uint32_t k = 0; k < stored; ++k) {
                    float v = img.pixels[p * c + std::min(k, c - 1)];
                    v = std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
                    EXPECT_EQ(back.pixels[p * stored + k], std::round(v * 255.0f) / 255.0f)
                        << ext << " " << p;
                }
        }
    }
}

TEST(ImageFile, JpegIsCloseAndDropsAlpha) {
    fs::path d = tmpDir();
    ImageData img = gradient(32, 32, 4);
    writeImage((d / "f.jpg").string(), img);
    ImageData back = readImage((d / "f.jpg").string());
    ASSERT_EQ(back.channels, 3u);
    double err = 0;
    for (size_t p = 0; p < 32 * 32; ++p)
        for (int k = 0; k < 3; ++k) err += std::abs(back.pixels[p * 3 + k] - img.pixels[p * 4 + k]);
    EXPECT_LT(err / (32 * 32 * 3), 0.01);  // quality 95 on a smooth ramp
}

TEST(ImageFile, SizeComesFromTheHeader) {
    fs::path d = tmpDir();
    for (const char* ext : {".exr", ".pfm", ".hdr", ".png", ".jpg", ".tga", ".bmp", ".ppm"}) {
        fs::path p = d / (std::string("s") + ext);
        writeImage(p.string(), gradient(11, 3, 3));
        uint32_t w = 0, h = 0;
        readImageSize(p.string(), w, h);
        EXPECT_EQ(w, 11u) << ext;
        EXPECT_EQ(h, 3u) << ext;
    }
}

TEST(ImageFile, SrgbDecodingAppliesToIntegerFilesOnly) {
    fs::path d = tmpDir();
    ImageData img = ImageData::make(2, 1, 4, 0.5f);
    writeImage((d / "l.png").string(), img);
    writeImage((d / "l.exr").string(), img);
    ImageData png = readImage((d / "l.png").string(), true);
    float stored = 128.0f / 255.0f;  // round(0.5 * 255)
    float linear = std::pow((stored + 0.055f) / 1.055f, 2.4f);
    EXPECT_NEAR(png.at(0, 0, 0), linear, 1e-6f);
    EXPECT_NEAR(png.at(0, 0, 0), 0.2158605f, 1e-6f);  // sRGB 128 is 0.2158605 linear
    EXPECT_EQ(png.at(0, 0, 3), stored);               // alpha is not decoded
    EXPECT_EQ(readImage((d / "l.exr").string(), true).at(0, 0, 0), 0.5f);
}

TEST(ImageFile, SixteenBitPngMadeFromTheSpec) {
    fs::path p = tmpDir() / "grey16.png";
    writeBytes(p, png16Grey(3, 2, {0, 1, 32768, 65535, 1000, 60000}));
    ImageData img = readImage(p.string());
    ASSERT_EQ(img.channels, 1u);
    ASSERT_EQ(img.width, 3u);
    ASSERT_EQ(img.height, 2u);
    const float expect[6] = {0, 1, 32768, 65535, 1000, 60000};
    for (int i = 0; i < 6; ++i) EXPECT_EQ(img.pixels[i], expect[i] / 65535.0f) << i;
}

TEST(ImageFile, SixteenBitPnmWithCommentsIsBigEndian) {
    fs::path p = tmpDir() / "grey16.pgm";
    // P5, a comment in the header, maxval 1000: values scale by 1/1000 and clamp at maxval.
    writeBytes(p, std::string("P5\n# made by hand\n3 1\n1000\n") +
                      std::string("\x00\x00\x01\xf4\x03\xe8", 6));
    ImageData img = readImage(p.string());
    ASSERT_EQ(img.channels, 1u);
    EXPECT_TRUE(img.pixels == std::vector<float>({0.0f, 500 / 1000.0f, 1.0f}));
}

TEST(ImageFile, BigEndianPfmReadsBottomRowFirst) {
    fs::path p = tmpDir() / "be.pfm";
    std::string bytes = "Pf\n2 2\n1.0\n";
    for (float v : {1.0f, 2.0f, 3.0f, 4.0f}) {  // bottom row 1 2, top row 3 4
        uint32_t u;
        std::memcpy(&u, &v, 4);
        bytes += std::string{char(u >> 24), char(u >> 16), char(u >> 8), char(u)};
    }
    writeBytes(p, bytes);
    ImageData img = readImage(p.string());
    ASSERT_EQ(img.channels, 1u);
    EXPECT_TRUE(img.pixels == std::vector<float>({3, 4, 1, 2}));
}

TEST(ImageFile, ExrChannelsComeAsRgbaThenByName) {
    fs::path p = tmpDir() / "bgrz.exr";
    const int w = 2, h = 1;
    // Planes written by OpenEXR directly: Z, B, G, R hold 40+x, 30+x, 20+x, 10+x.
    std::vector<float> planes[4];
    const char* names[4] = {"Z", "B", "G", "R"};
    Imf::Header header(w, h);
    Imf::FrameBuffer fb;
    for (int c = 0; c < 4; ++c) {
        planes[c] = {float(40 - 10 * c), float(41 - 10 * c)};
        header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, (char*)planes[c].data(), 4, 4 * w));
    }
    {
        Imf::OutputFile out(p.string().c_str(), header);
        out.setFrameBuffer(fb);
        out.writePixels(h);
    }
    ImageData img = readImage(p.string());
    ASSERT_EQ(img.channels, 4u);
    EXPECT_TRUE(img.pixels == std::vector<float>({10, 20, 30, 40, 11, 21, 31, 41}));
}

TEST(ImageFile, MalformedFilesAreNamedErrors) {
    fs::path d = tmpDir();
    // headerBad: the header itself is malformed, so readImageSize fails too.
    auto expectError = [&](const std::string& name, const std::string& bytes,
                           const std::string& what, bool headerBad = true) {
        fs::path p = d / name;
        writeBytes(p, bytes);
        std::string err = errorOf([&] { readImage(p.string()); });
        EXPECT_NE(err.find(p.string()), std::string::npos) << name << ": " << err;
        EXPECT_NE(err.find(what), std::string::npos) << name << ": " << err;
        uint32_t w, h;
        if (headerBad) {
            EXPECT_NE(errorOf([&] { readImageSize(p.string(), w, h); }), "") << name;
        }
    };
    expectError("empty.png", "", "cannot read image");
    expectError("text.png", "hello, not an image", "not a supported format");
    expectError("trunc.pfm", "PF\n4 4\n-1.0\n" + std::string(20, 'x'), "truncated", false);
    expectError("neg.pfm", "PF\n-4 4\n-1.0\n", "bad size");
    expectError("scale.pfm", "PF\n4 4\nnan\n", "bad size or scale");
    expectError("huge.pfm", "Pf\n100000 100000\n-1.0\n", "too large");
    expectError("zero.pfm", "Pf\n0 4\n-1.0\n", "no pixels");
    expectError("exr.exr", std::string("\x76\x2f\x31\x01", 4) + "garbage", "cannot read EXR");

    // A PNG whose pixel data is cut off.
    writeImage((d / "whole.png").string(), gradient(64, 64, 3));
    std::ifstream in(d / "whole.png", std::ios::binary);
    std::string png((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    expectError("cut.png", png.substr(0, png.size() / 2), "cannot decode PNG image", false);
    writeImage((d / "whole.jpg").string(), gradient(64, 64, 3));
    std::ifstream jin(d / "whole.jpg", std::ios::binary);
    std::string jpg((std::istreambuf_iterator<char>(jin)), std::istreambuf_iterator<char>());
    expectError("cut.jpg", jpg.substr(0, 40), "cannot decode JPEG image");
    // Truncated files that stb_image would have filled with zeros, and a corrupt RLE run.
    for (const char* ext : {".hdr", ".bmp", ".tga"}) {
        writeImage((d / (std::string("whole") + ext)).string(), gradient(64, 16, 3, 2.0f));
        std::ifstream win(d / (std::string("whole") + ext), std::ios::binary);
        std::string whole((std::istreambuf_iterator<char>(win)), std::istreambuf_iterator<char>());
        expectError(std::string("cut") + ext, whole.substr(0, whole.size() * 2 / 3), "truncated",
                    false);
    }
    expectError(
        "run.hdr",
        std::string("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 8\n\x02\x02\x00\x08", 49) +
            std::string("\xff\x01", 2),
        "a run past the end of the line", false);
    expectError("xyze.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\x01\x01\x01\x80",
                "not supported");
    expectError("flip.hdr", "#?RADIANCE\n\n+Y 1 +X 1\n\x01\x01\x01\x80", "'-Y H +X W' is");
    expectError("ascii.ppm", "P3\n1 1\n255\n0 0 0\n", "P3 is not supported");
    expectError("trunc.ppm", "P6\n4 4\n255\n" + std::string(10, 'x'), "truncated", false);
    expectError("maxval.ppm", "P5\n4 4\n70000\n", "bad maximum value");

    EXPECT_NE(
        errorOf([&] { readImage((d / "missing.exr").string()); }).find("image file not found"),
        std::string::npos);
    EXPECT_NE(errorOf([&] { readImage(d.string()); }).find("is a directory"), std::string::npos);
}

// fuzz_image's first finding: a JPEG whose Huffman table made Debian's stb_image index out of
// bounds (UBSan). JPEG now goes to libjpeg-turbo, which names the problem.
TEST(ImageFile, FuzzerFindingsAreNamedErrors) {
    const std::string path = std::string(LOOM_TEST_DATA) + "/fuzz/stb_jpeg_huffman.jpg";
    std::string err = errorOf([&] { readImage(path); });
    EXPECT_NE(err.find(path + ": cannot decode JPEG image"), std::string::npos) << err;
}

TEST(ImageFile, UnwritableFormatsAreRefusedBeforeAnythingIsWritten) {
    fs::path d = tmpDir();
    std::string err = errorOf([&] { checkImagePath((d / "x.tif").string()); });
    EXPECT_NE(err.find("no image writer for '.tif'"), std::string::npos) << err;
    EXPECT_NE(errorOf([&] { writeImage((d / "x.webp").string(), gradient(2, 2, 3)); }), "");
    EXPECT_FALSE(fs::exists(d / "x.webp"));
    EXPECT_NE(errorOf([&] { checkImagePath((d / "noext").string()); }).find("needs an extension"),
              std::string::npos);
    // Upper-case extensions are the same formats.
    writeImage((d / "UP.PNG").string(), gradient(2, 2, 3));
    EXPECT_EQ(readImage((d / "UP.PNG").string()).width, 2u);
}
