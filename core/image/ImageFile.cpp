// Image files: the formats Mitsuba 3's Bitmap reads and writes. OpenEXR for EXR, stb_image
// (Debian's libstb) for PNG, JPEG, Radiance HDR, TGA, BMP and PNM, and PFM by hand. The
// format is chosen by the file's magic bytes when reading and by the extension when writing.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "core/image/Image.h"
#include "core/util/AtomicFile.h"
#include "core/util/Error.h"

namespace loom {

namespace {

namespace fs = std::filesystem;

// Larger images are refused before anything is allocated: a corrupt header must not make
// Loom try to allocate terabytes.
constexpr uint64_t kMaxPixels = uint64_t(1) << 28;
constexpr uint32_t kMaxSide = 1u << 16;

enum class FileFormat { Exr, Pfm, Stb };

std::string lowerExt(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

std::vector<uint8_t> readFileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError(path + ": cannot open image file");
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                               std::istreambuf_iterator<char>());
    if (in.bad()) throw UserError(path + ": cannot read image file");
    return bytes;
}

FileFormat sniff(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char magic[4] = {};
    in.read(magic, 4);
    static const unsigned char exr[4] = {0x76, 0x2f, 0x31, 0x01};
    if (in.gcount() == 4 && std::memcmp(magic, exr, 4) == 0) return FileFormat::Exr;
    if (in.gcount() >= 3 && magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f') &&
        std::isspace(static_cast<unsigned char>(magic[2])))
        return FileFormat::Pfm;
    return FileFormat::Stb;
}

void checkSize(const std::string& path, uint64_t width, uint64_t height) {
    if (width == 0 || height == 0)
        throw UserError(path + ": image has no pixels (" + std::to_string(width) + "x" +
                        std::to_string(height) + ")");
    if (width > kMaxSide || height > kMaxSide || width * height > kMaxPixels)
        throw UserError(path + ": image is too large (" + std::to_string(width) + "x" +
                        std::to_string(height) + "; at most " + std::to_string(kMaxSide) +
                        " per side and 2^28 pixels)");
}

// --- OpenEXR -------------------------------------------------------------------------------

// R, G, B, A first (in that order), then the other channels by name, as OpenImageIO does.
std::vector<std::string> exrChannelOrder(const Imf::ChannelList& list) {
    std::vector<std::string> names, rest;
    for (const char* n : {"R", "G", "B", "A"})
        if (list.findChannel(n)) names.push_back(n);
    if (names.empty() && list.findChannel("Y")) {
        names.push_back("Y");
        if (list.findChannel("A")) names.push_back("A");
    }
    for (auto it = list.begin(); it != list.end(); ++it)
        if (std::find(names.begin(), names.end(), it.name()) == names.end())
            rest.push_back(it.name());
    names.insert(names.end(), rest.begin(), rest.end());
    return names;
}

ImageData readExr(const std::string& path, bool headerOnly) {
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        uint64_t w = uint64_t(int64_t(dw.max.x) - dw.min.x + 1);
        uint64_t h = uint64_t(int64_t(dw.max.y) - dw.min.y + 1);
        if (dw.max.x < dw.min.x || dw.max.y < dw.min.y) w = h = 0;
        checkSize(path, w, h);
        std::vector<std::string> names = exrChannelOrder(file.header().channels());
        if (names.empty()) throw UserError(path + ": EXR file has no channels");
        ImageData img;
        img.width = uint32_t(w);
        img.height = uint32_t(h);
        img.channels = uint32_t(names.size());
        if (headerOnly) return img;
        img.pixels.assign(size_t(w) * h * img.channels, 0.0f);
        Imf::FrameBuffer fb;
        const size_t xs = sizeof(float) * img.channels, ys = xs * w;
        for (size_t c = 0; c < names.size(); ++c)
            fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, img.pixels.data() + c, dw, xs, ys));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        return img;
    } catch (const UserError&) {
        throw;
    } catch (const std::exception& e) {
        throw UserError(path + ": cannot read EXR image: " + e.what());
    }
}

void writeExr(const std::string& file, const std::string& path, const ImageData& image,
              uint32_t channels) {
    static const char* names[4][4] = {{"Y"}, {"R", "G"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
    try {
        Imf::Header header(int(image.width), int(image.height));
        header.compression() = Imf::ZIP_COMPRESSION;
        Imf::FrameBuffer fb;
        const size_t xs = sizeof(float) * image.channels, ys = xs * image.width;
        for (uint32_t c = 0; c < channels; ++c) {
            header.channels().insert(names[channels - 1][c], Imf::Channel(Imf::FLOAT));
            fb.insert(names[channels - 1][c],
                      Imf::Slice(Imf::FLOAT, (char*)(image.pixels.data() + c), xs, ys));
        }
        Imf::OutputFile out(file.c_str(), header);
        out.setFrameBuffer(fb);
        out.writePixels(int(image.height));
    } catch (const std::exception& e) {
        throw UserError(path + ": cannot write EXR image: " + e.what());
    }
}

// --- PFM (Portable Float Map): "PF" (RGB) or "Pf" (grey), width height, scale (negative:
// little-endian), then rows bottom to top. -------------------------------------------------

ImageData readPfm(const std::string& path, bool headerOnly) {
    std::vector<uint8_t> bytes = readFileBytes(path);
    std::string head(bytes.begin(), bytes.begin() + std::min<size_t>(bytes.size(), 256));
    size_t pos = 0;
    auto token = [&]() {
        while (pos < head.size() && std::isspace(static_cast<unsigned char>(head[pos]))) ++pos;
        size_t start = pos;
        while (pos < head.size() && !std::isspace(static_cast<unsigned char>(head[pos]))) ++pos;
        return head.substr(start, pos - start);
    };
    std::string magic = token(), ws = token(), hs = token(), ss = token();
    if ((magic != "PF" && magic != "Pf") || pos >= head.size())
        throw UserError(path + ": not a PFM file (bad header)");
    ++pos;  // the single whitespace character after the scale
    uint64_t w = 0, h = 0;
    double scale = 0;
    auto digits = [](const std::string& t) {
        return !t.empty() && t.size() <= 9 &&
               std::all_of(t.begin(), t.end(), [](unsigned char c) { return std::isdigit(c); });
    };
    try {
        if (!digits(ws) || !digits(hs)) throw std::invalid_argument(ws);
        size_t used = 0;
        w = std::stoull(ws, &used);
        if (used != ws.size()) throw std::invalid_argument(ws);
        h = std::stoull(hs, &used);
        if (used != hs.size()) throw std::invalid_argument(hs);
        scale = std::stod(ss, &used);
        if (used != ss.size() || !std::isfinite(scale) || scale == 0)
            throw std::invalid_argument(ss);
    } catch (const std::exception&) {
        throw UserError(path + ": not a PFM file (bad size or scale in the header)");
    }
    checkSize(path, w, h);
    ImageData img;
    img.width = uint32_t(w);
    img.height = uint32_t(h);
    img.channels = magic == "PF" ? 3 : 1;
    if (headerOnly) return img;
    size_t count = size_t(w) * h * img.channels;
    if (bytes.size() - pos < count * 4)
        throw UserError(path + ": PFM file is truncated (" + std::to_string(bytes.size() - pos) +
                        " bytes of pixels, " + std::to_string(count * 4) + " expected)");
    img.pixels.resize(count);
    const bool bigEndian = scale > 0;
    const size_t row = size_t(w) * img.channels;
    for (size_t y = 0; y < h; ++y)
        for (size_t i = 0; i < row; ++i) {
            uint8_t b[4];
            std::memcpy(b, bytes.data() + pos + (y * row + i) * 4, 4);
            if (bigEndian) std::swap(b[0], b[3]), std::swap(b[1], b[2]);
            float v;
            std::memcpy(&v, b, 4);
            img.pixels[(h - 1 - y) * row + i] = v;
        }
    return img;
}

std::vector<uint8_t> encodePfm(const ImageData& image, uint32_t channels) {
    const uint32_t out = channels == 1 ? 1 : 3;
    std::string head = std::string(out == 3 ? "PF" : "Pf") + "\n" + std::to_string(image.width) +
                       " " + std::to_string(image.height) + "\n-1.0\n";
    std::vector<uint8_t> bytes(head.begin(), head.end());
    bytes.reserve(bytes.size() + size_t(image.width) * image.height * out * 4);
    for (uint32_t y = image.height; y-- > 0;)
        for (uint32_t x = 0; x < image.width; ++x)
            for (uint32_t c = 0; c < out; ++c) {
                float v = c < channels ? image.at(x, y, c) : 0.0f;
                uint8_t b[4];
                std::memcpy(b, &v, 4);  // x86-64 and arm64 are little-endian, as "-1.0" says
                bytes.insert(bytes.end(), b, b + 4);
            }
    return bytes;
}

// --- stb_image: PNG, JPEG, HDR, TGA, BMP, PNM, GIF, PSD --------------------------------------

ImageData readStb(const std::string& path, bool headerOnly, bool& integer) {
    std::vector<uint8_t> bytes = readFileBytes(path);
    if (bytes.size() > size_t(INT32_MAX)) throw UserError(path + ": image file is too large");
    const auto* data = bytes.data();
    const int size = int(bytes.size());
    int w = 0, h = 0, n = 0;
    if (!stbi_info_from_memory(data, size, &w, &h, &n))
        throw UserError(path +
                        ": cannot read image: not a supported format (EXR, PNG, JPEG, "
                        "HDR, PFM, TGA, BMP, PPM): " +
                        std::string(stbi_failure_reason() ? stbi_failure_reason() : "unknown"));
    checkSize(path, uint64_t(w), uint64_t(h));
    ImageData img;
    img.width = uint32_t(w);
    img.height = uint32_t(h);
    img.channels = uint32_t(n);
    integer = !stbi_is_hdr_from_memory(data, size);
    if (headerOnly) return img;
    img.pixels.resize(size_t(w) * h * n);
    int rw = 0, rh = 0, rn = 0;
    auto fail = [&]() {
        return UserError(path + ": cannot decode image: " +
                         std::string(stbi_failure_reason() ? stbi_failure_reason() : "unknown"));
    };
    auto check = [&](void* p) {
        if (!p) throw fail();
        if (rw != w || rh != h || rn != n) {
            stbi_image_free(p);
            throw UserError(path + ": cannot decode image: the header and the data disagree");
        }
    };
    if (!integer) {
        float* p = stbi_loadf_from_memory(data, size, &rw, &rh, &rn, 0);
        check(p);
        std::copy(p, p + img.pixels.size(), img.pixels.begin());
        stbi_image_free(p);
    } else if (stbi_is_16_bit_from_memory(data, size)) {
        stbi_us* p = stbi_load_16_from_memory(data, size, &rw, &rh, &rn, 0);
        check(p);
        for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = p[i] / 65535.0f;
        stbi_image_free(p);
    } else {
        stbi_uc* p = stbi_load_from_memory(data, size, &rw, &rh, &rn, 0);
        check(p);
        for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = p[i] / 255.0f;
        stbi_image_free(p);
    }
    return img;
}

void appendBytes(void* context, void* data, int size) {
    auto* out = static_cast<std::vector<uint8_t>*>(context);
    out->insert(out->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
}

std::vector<uint8_t> quantize8(const ImageData& image, uint32_t channels) {
    std::vector<uint8_t> q(size_t(image.width) * image.height * channels);
    for (size_t p = 0; p < size_t(image.width) * image.height; ++p)
        for (uint32_t c = 0; c < channels; ++c) {
            float v = image.pixels[p * image.channels + c];
            v = std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f);
            q[p * channels + c] = uint8_t(std::lround(v * 255.0f));
        }
    return q;
}

std::vector<uint8_t> encodePpm(const ImageData& image, uint32_t channels) {
    std::string head = std::string(channels == 1 ? "P5" : "P6") + "\n" +
                       std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
    std::vector<uint8_t> bytes(head.begin(), head.end());
    const uint32_t out = channels == 1 ? 1 : 3;
    std::vector<uint8_t> q = quantize8(image, channels);
    for (size_t p = 0; p < size_t(image.width) * image.height; ++p)
        for (uint32_t c = 0; c < out; ++c) bytes.push_back(c < channels ? q[p * channels + c] : 0);
    return bytes;
}

// Channels each writer stores: alpha is dropped where the format has none.
uint32_t storedChannels(const std::string& ext, uint32_t channels) {
    channels = std::min(channels, 4u);
    if ((ext == ".hdr" || ext == ".jpg" || ext == ".jpeg" || ext == ".pfm" || ext == ".ppm") &&
        channels == 4)
        return 3;
    return channels;
}

const char* kWritable = ".exr, .hdr, .pfm, .png, .jpg, .tga, .bmp, .ppm";

bool writable(const std::string& ext) {
    for (const char* e : {".exr", ".hdr", ".pfm", ".png", ".jpg", ".jpeg", ".tga", ".bmp", ".ppm"})
        if (ext == e) return true;
    return false;
}

void writeBytes(const std::string& file, const std::string& path,
                const std::vector<uint8_t>& bytes) {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    out.flush();
    if (!out) throw UserError(path + ": cannot write image (disk full?)");
}

ImageData readAny(const std::string& path, bool headerOnly, bool& integer) {
    if (!fs::exists(path)) throw UserError(path + ": image file not found");
    if (fs::is_directory(path)) throw UserError(path + ": is a directory, not an image file");
    integer = false;
    switch (sniff(path)) {
        case FileFormat::Exr:
            return readExr(path, headerOnly);
        case FileFormat::Pfm:
            return readPfm(path, headerOnly);
        case FileFormat::Stb:
            break;
    }
    return readStb(path, headerOnly, integer);
}

float srgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

ImageData readImage(const std::string& path, bool linearize) {
    bool integer = false;
    ImageData img = readAny(path, false, integer);
    if (linearize && integer)
        for (size_t i = 0; i < img.pixels.size(); ++i)
            if (img.channels < 4 || i % img.channels != 3)
                img.pixels[i] = srgbToLinear(img.pixels[i]);
    return img;
}

void readImageSize(const std::string& path, uint32_t& width, uint32_t& height) {
    bool integer = false;
    ImageData img = readAny(path, true, integer);
    width = img.width;
    height = img.height;
}

void checkImagePath(const std::string& path) {
    std::string ext = lowerExt(path);
    if (ext.empty()) throw UserError(path + ": output file needs an extension (.exr, .png, ...)");
    if (!writable(ext))
        throw UserError(path + ": no image writer for '" + ext + "' (Loom writes " + kWritable +
                        ")");
    checkWritable(path, "image");
}

void writeImage(const std::string& path, const ImageData& image) {
    const std::string ext = lowerExt(path);
    if (ext.empty()) throw UserError(path + ": output file needs an extension (.exr, .png, ...)");
    if (!writable(ext))
        throw UserError(path + ": no image writer for '" + ext + "' (Loom writes " + kWritable +
                        ")");
    if (image.width == 0 || image.height == 0 || image.channels == 0 ||
        image.pixels.size() != size_t(image.width) * image.height * image.channels)
        throw UserError(path + ": cannot write an empty or malformed image (" +
                        std::to_string(image.width) + "x" + std::to_string(image.height) + "x" +
                        std::to_string(image.channels) + ")");
    const uint32_t channels = storedChannels(ext, image.channels);
    writeFileAtomic(path, "image", [&](const std::string& file) {
        if (ext == ".exr") {
            writeExr(file, path, image, channels);
        } else {
            std::vector<uint8_t> bytes;
            const int w = int(image.width), h = int(image.height), n = int(channels);
            int ok = 1;
            if (ext == ".pfm") {
                bytes = encodePfm(image, channels);
            } else if (ext == ".ppm") {
                bytes = encodePpm(image, channels);
            } else if (ext == ".hdr") {
                std::vector<float> f(size_t(w) * h * n);
                for (size_t p = 0; p < size_t(w) * h; ++p)
                    for (int c = 0; c < n; ++c) f[p * n + c] = image.pixels[p * image.channels + c];
                ok = stbi_write_hdr_to_func(appendBytes, &bytes, w, h, n, f.data());
            } else {
                std::vector<uint8_t> q = quantize8(image, channels);
                if (ext == ".png")
                    ok = stbi_write_png_to_func(appendBytes, &bytes, w, h, n, q.data(), w * n);
                else if (ext == ".jpg" || ext == ".jpeg")
                    ok = stbi_write_jpg_to_func(appendBytes, &bytes, w, h, n, q.data(), 95);
                else if (ext == ".tga")
                    ok = stbi_write_tga_to_func(appendBytes, &bytes, w, h, n, q.data());
                else
                    ok = stbi_write_bmp_to_func(appendBytes, &bytes, w, h, n, q.data());
            }
            if (!ok || bytes.empty()) throw UserError(path + ": cannot encode image");
            writeBytes(file, path, bytes);
        }
        // Not every writer reports a short write (a full disk, a file-size limit), so the file
        // is read back whole before it replaces the target.
        if (fs::is_regular_file(file)) {
            ImageData back;
            try {
                back = readImage(file);
            } catch (const UserError& e) {
                throw UserError(path +
                                ": the written image does not read back (disk full?): " + e.what());
            }
            if (back.width != image.width || back.height != image.height)
                throw UserError(path + ": the written image does not read back (disk full?)");
        }
    });
}

}  // namespace loom
