// Image files: the formats Mitsuba 3's Bitmap reads and writes. Reading: OpenEXR, libpng and
// libjpeg-turbo (hardened against malformed files: they are fuzzed upstream), PFM, PNM and
// Radiance HDR by hand, and stb_image (Debian's libstb) for TGA, BMP, GIF and PSD. stb_image
// is not meant for untrusted files, and fuzz_image found undefined behaviour in its PNG, JPEG
// and PNM decoders within seconds, so those never reach it. Writing: OpenEXR, stb_image_write
// (PNG, JPEG, HDR, TGA, BMP), PFM and PPM by hand. The format is chosen by the file's magic
// bytes when reading and by the extension when writing.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <jpeglib.h>
#include <png.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
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
// Loom try to allocate terabytes. 2^28 pixels is a 16k x 16k texture (4 GiB as float RGBA);
// the fuzz build stops at 2^20 so that libFuzzer's memory and time limits (4 GB, 10 s under
// ASan) mean a real blow-up or hang, not a large image.
#ifdef LOOM_FUZZ_BUILD
constexpr uint64_t kMaxPixels = uint64_t(1) << 20;
#else
constexpr uint64_t kMaxPixels = uint64_t(1) << 28;
#endif
constexpr uint32_t kMaxSide = 1u << 16;

enum class FileFormat { Exr, Pfm, Png, Jpeg, Pnm, Rgbe, Stb, Unknown };

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

// stb_image only ever sees the formats it is used for (its own format tests are weaker: a file
// starting FF D8 is a JPEG to it, "P5" a PNM), and TGA, which has no magic, only by extension.
FileFormat sniff(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    unsigned char magic[11] = {};
    in.read(reinterpret_cast<char*>(magic), sizeof(magic));
    const auto n = size_t(in.gcount());
    auto starts = [&](const char* m, size_t len) {
        return n >= len && std::memcmp(magic, m, len) == 0;
    };
    if (starts("\x76\x2f\x31\x01", 4)) return FileFormat::Exr;
    if (starts("\x89PNG", 4)) return FileFormat::Png;
    if (starts("\xff\xd8", 2)) return FileFormat::Jpeg;
    if (n >= 2 && magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f')) return FileFormat::Pfm;
    if (n >= 2 && magic[0] == 'P' && magic[1] >= '1' && magic[1] <= '7') return FileFormat::Pnm;
    if (starts("#?RADIANCE\n", 11) || starts("#?RGBE\n", 7)) return FileFormat::Rgbe;
    if (starts("BM", 2) || starts("GIF87a", 6) || starts("GIF89a", 6) || starts("8BPS", 4) ||
        lowerExt(path) == ".tga")
        return FileFormat::Stb;
    return FileFormat::Unknown;
}

void checkSize(const std::string& path, uint64_t width, uint64_t height) {
    if (width == 0 || height == 0)
        throw UserError(path + ": image has no pixels (" + std::to_string(width) + "x" +
                        std::to_string(height) + ")");
    if (width > kMaxSide || height > kMaxSide || width * height > kMaxPixels)
        throw UserError(path + ": image is too large (" + std::to_string(width) + "x" +
                        std::to_string(height) + "; at most " + std::to_string(kMaxSide) +
                        " per side and " + std::to_string(kMaxPixels) + " pixels)");
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

// --- PNG (libpng) ----------------------------------------------------------------------------

struct PngReader {
    const std::string& path;
    std::string error;
};

void pngError(png_structp png, png_const_charp message) {
    static_cast<PngReader*>(png_get_error_ptr(png))->error = message;
    png_longjmp(png, 1);
}
void pngWarning(png_structp, png_const_charp) {}

struct PngSource {
    const std::vector<uint8_t>& bytes;
    size_t pos = 0;
};

void pngRead(png_structp png, png_bytep out, png_size_t count) {
    auto* src = static_cast<PngSource*>(png_get_io_ptr(png));
    if (count > src->bytes.size() - src->pos) png_error(png, "file is truncated");
    std::memcpy(out, src->bytes.data() + src->pos, count);
    src->pos += count;
}

// 8- and 16-bit files come as stored (no gamma conversion); palettes and low bit depths are
// expanded, tRNS becomes alpha.
ImageData readPng(const std::string& path, bool headerOnly) {
    std::vector<uint8_t> bytes = readFileBytes(path);
    PngReader reader{path, {}};
    PngSource source{bytes, 0};
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &reader, pngError, pngWarning);
    if (!png) throw UserError(path + ": cannot read PNG image: out of memory");
    png_infop info = png_create_info_struct(png);
    ImageData img;
    std::vector<uint8_t> raw;
    std::vector<png_bytep> rows;
    bool sixteen = false;
    // Nothing with a destructor is created between setjmp and the reads that may longjmp.
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        throw UserError(path + ": cannot decode PNG image: " + reader.error);
    }
    png_set_read_fn(png, &source, pngRead);
    png_set_user_limits(png, kMaxSide, kMaxSide);
    png_read_info(png, info);
    const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    if (uint64_t(w) * h > kMaxPixels) png_error(png, "image is too large");
    const int depth = png_get_bit_depth(png, info), type = png_get_color_type(png, info);
    if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
    if (depth == 16) png_set_swap(png);  // little-endian uint16 in memory
    png_read_update_info(png, info);
    sixteen = png_get_bit_depth(png, info) == 16;
    img.width = w;
    img.height = h;
    img.channels = png_get_channels(png, info);
    if (!headerOnly) {
        const size_t stride = png_get_rowbytes(png, info);
        raw.resize(stride * h);
        rows.resize(h);
        for (png_uint_32 y = 0; y < h; ++y) rows[y] = raw.data() + y * stride;
        png_read_image(png, rows.data());
        png_read_end(png, nullptr);
    }
    png_destroy_read_struct(&png, &info, nullptr);
    checkSize(path, img.width, img.height);
    if (headerOnly) return img;
    img.pixels.resize(size_t(img.width) * img.height * img.channels);
    if (sixteen) {
        for (size_t i = 0; i < img.pixels.size(); ++i) {
            uint16_t v;
            std::memcpy(&v, raw.data() + 2 * i, 2);
            img.pixels[i] = v / 65535.0f;
        }
    } else {
        for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = raw[i] / 255.0f;
    }
    return img;
}

// --- JPEG (libjpeg-turbo) ---------------------------------------------------------------------

struct JpegError {
    jpeg_error_mgr mgr;
    std::jmp_buf jump;
    char message[JMSG_LENGTH_MAX];
};

void jpegErrorExit(j_common_ptr cinfo) {
    auto* err = reinterpret_cast<JpegError*>(cinfo->err);
    cinfo->err->format_message(cinfo, err->message);
    std::longjmp(err->jump, 1);
}
void jpegMessage(j_common_ptr) {}

ImageData readJpeg(const std::string& path, bool headerOnly) {
    std::vector<uint8_t> bytes = readFileBytes(path);
    jpeg_decompress_struct cinfo;
    JpegError err;
    cinfo.err = jpeg_std_error(&err.mgr);
    err.mgr.error_exit = jpegErrorExit;
    err.mgr.output_message = jpegMessage;
    std::vector<uint8_t> raw;
    ImageData img;
    if (setjmp(err.jump)) {
        jpeg_destroy_decompress(&cinfo);
        throw UserError(path + ": cannot decode JPEG image: " + err.message);
    }
    jpeg_create_decompress(&cinfo);
    jpeg_mem_src(&cinfo, bytes.data(), static_cast<unsigned long>(bytes.size()));
    jpeg_read_header(&cinfo, TRUE);
    if (cinfo.image_width > kMaxSide || cinfo.image_height > kMaxSide ||
        uint64_t(cinfo.image_width) * cinfo.image_height > kMaxPixels) {
        std::snprintf(err.message, sizeof(err.message), "image is too large (%ux%u)",
                      cinfo.image_width, cinfo.image_height);
        std::longjmp(err.jump, 1);
    }
    // CMYK and YCCK (Adobe) files are converted to RGB by the library where it can; others fail.
    cinfo.out_color_space = cinfo.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
    img.width = cinfo.image_width;
    img.height = cinfo.image_height;
    img.channels = cinfo.num_components == 1 ? 1 : 3;
    if (!headerOnly) {
        jpeg_start_decompress(&cinfo);
        const size_t stride = size_t(cinfo.output_width) * cinfo.output_components;
        raw.resize(stride * cinfo.output_height);
        while (cinfo.output_scanline < cinfo.output_height) {
            JSAMPROW row = raw.data() + stride * cinfo.output_scanline;
            jpeg_read_scanlines(&cinfo, &row, 1);
        }
        jpeg_finish_decompress(&cinfo);
    }
    jpeg_destroy_decompress(&cinfo);
    checkSize(path, img.width, img.height);
    if (headerOnly) return img;
    img.pixels.resize(raw.size());
    for (size_t i = 0; i < raw.size(); ++i) img.pixels[i] = raw[i] / 255.0f;
    return img;
}

// --- PNM: binary P5 (grey) and P6 (RGB), 8 or 16 bit (big-endian) -----------------------------

ImageData readPnm(const std::string& path, bool headerOnly) {
    std::vector<uint8_t> bytes = readFileBytes(path);
    size_t pos = 2;
    auto token = [&]() {
        for (;;) {  // whitespace and '#' comments
            while (pos < bytes.size() && std::isspace(bytes[pos])) ++pos;
            if (pos < bytes.size() && bytes[pos] == '#')
                while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
            else
                break;
        }
        std::string t;
        while (pos < bytes.size() && std::isdigit(bytes[pos]) && t.size() < 10)
            t += char(bytes[pos++]);
        if (t.empty() || t.size() > 9) throw UserError(path + ": not a PNM file (bad header)");
        return std::stoul(t);
    };
    if (bytes[1] != '5' && bytes[1] != '6')
        throw UserError(path + ": PNM type P" + std::string(1, char(bytes[1])) +
                        " is not supported (binary P5 and P6 are)");
    const uint64_t w = token(), h = token(), maxval = token();
    if (maxval == 0 || maxval > 65535 || pos >= bytes.size() || !std::isspace(bytes[pos]))
        throw UserError(path + ": not a PNM file (bad maximum value)");
    ++pos;
    checkSize(path, w, h);
    ImageData img;
    img.width = uint32_t(w);
    img.height = uint32_t(h);
    img.channels = bytes[1] == '5' ? 1 : 3;
    if (headerOnly) return img;
    const size_t count = size_t(w) * h * img.channels, size = maxval > 255 ? 2 : 1;
    if (bytes.size() - pos < count * size) throw UserError(path + ": PNM file is truncated");
    img.pixels.resize(count);
    for (size_t i = 0; i < count; ++i) {
        const uint8_t* b = bytes.data() + pos + i * size;
        uint32_t v = size == 2 ? (uint32_t(b[0]) << 8) | b[1] : b[0];
        img.pixels[i] = float(std::min<uint32_t>(v, uint32_t(maxval))) / float(maxval);
    }
    return img;
}

// --- Radiance RGBE (.hdr): header lines, "-Y H +X W", then scanlines, flat or new-style RLE
// (Greg Ward's format; the mantissa scale 2^(e-136) as stb_image and Mitsuba read it). ---------

ImageData readRgbe(const std::string& path, bool headerOnly) {
    std::vector<uint8_t> bytes = readFileBytes(path);
    size_t pos = 0;
    auto line = [&]() {
        std::string l;
        while (pos < bytes.size() && bytes[pos] != '\n' && l.size() < 4096) l += char(bytes[pos++]);
        if (pos >= bytes.size()) throw UserError(path + ": Radiance HDR header is truncated");
        ++pos;
        return l;
    };
    line();  // #?RADIANCE or #?RGBE
    for (std::string l = line(); !l.empty(); l = line())
        if (l.rfind("FORMAT=", 0) == 0 && l != "FORMAT=32-bit_rle_rgbe")
            throw UserError(path + ": Radiance HDR " + l +
                            " is not supported (32-bit_rle_rgbe is)");
    char ys[3] = {}, xs[3] = {};
    unsigned long h = 0, w = 0;
    std::string res = line();
    char tail = 0;
    if (std::sscanf(res.c_str(), "%2s %lu %2s %lu%c", ys, &h, xs, &w, &tail) != 4 ||
        std::string(ys) != "-Y" || std::string(xs) != "+X")
        throw UserError(path + ": Radiance HDR resolution line '" + res.substr(0, 40) +
                        "' is not supported ('-Y H +X W' is)");
    checkSize(path, w, h);
    ImageData img;
    img.width = uint32_t(w);
    img.height = uint32_t(h);
    img.channels = 3;
    if (headerOnly) return img;
    img.pixels.resize(size_t(w) * h * 3);
    std::vector<uint8_t> rgbe(size_t(w) * 4);
    auto truncated = [&]() { return UserError(path + ": Radiance HDR file is truncated"); };
    for (size_t y = 0; y < h; ++y) {
        const bool rle = w >= 8 && w < 0x8000 && bytes.size() - pos >= 4 && bytes[pos] == 2 &&
                         bytes[pos + 1] == 2 &&
                         ((size_t(bytes[pos + 2]) << 8) | bytes[pos + 3]) == w;
        if (!rle) {  // flat RGBE quadruples
            if (bytes.size() - pos < rgbe.size()) throw truncated();
            std::memcpy(rgbe.data(), bytes.data() + pos, rgbe.size());
            pos += rgbe.size();
        } else {
            pos += 4;
            for (size_t c = 0; c < 4; ++c)
                for (size_t x = 0; x < w;) {
                    if (pos >= bytes.size()) throw truncated();
                    size_t count = bytes[pos++];
                    const bool run = count > 128;
                    if (run) count -= 128;
                    if (count == 0 || count > w - x)
                        throw UserError(path + ": Radiance HDR scanline " + std::to_string(y) +
                                        " is corrupt (a run past the end of the line)");
                    if (bytes.size() - pos < (run ? 1 : count)) throw truncated();
                    for (size_t k = 0; k < count; ++k, ++x)
                        rgbe[x * 4 + c] = run ? bytes[pos] : bytes[pos + k];
                    pos += run ? 1 : count;
                }
        }
        for (size_t x = 0; x < w; ++x) {
            const uint8_t* q = rgbe.data() + x * 4;
            const float f = q[3] ? std::ldexp(1.0f, int(q[3]) - 136) : 0.0f;
            for (int c = 0; c < 3; ++c) img.pixels[(y * w + x) * 3 + c] = q[c] * f;
        }
    }
    return img;
}

// --- stb_image: TGA, BMP, GIF, PSD ---------------------------------------------------------------

// stb_image reads past the end of a BMP or TGA as zeros: a truncated file would load as a
// partly black image without a word. The header (and, for RLE TGA, the packet headers) says
// how many bytes there must be.
void checkDeclaredSize(const std::string& path, const std::vector<uint8_t>& b, int w, int h) {
    auto le16 = [&](size_t i) { return uint32_t(b[i]) | (uint32_t(b[i + 1]) << 8); };
    auto le32 = [&](size_t i) { return le16(i) | (le16(i + 2) << 16); };
    uint64_t need = 0;
    if (b.size() >= 34 && b[0] == 'B' && b[1] == 'M') {
        const uint32_t compression = le32(30), bpp = le16(28);
        if (compression == 0 || compression == 3)  // BI_RGB, BI_BITFIELDS
            need = le32(10) + uint64_t(h) * ((uint64_t(w) * bpp + 31) / 32 * 4);
    } else if (b.size() >= 18 && ((b[2] & 7) >= 1 && (b[2] & 7) <= 3)) {  // TGA
        const uint64_t pixelBytes = (b[16] + 7) / 8;
        need = 18 + b[0] + (b[1] ? uint64_t(le16(5)) * ((b[7] + 7) / 8) : 0);
        if (b[2] & 8) {  // RLE packets: a header byte, then one pixel (run) or count pixels
            for (uint64_t pixels = 0; pixels < uint64_t(w) * h && need < b.size();) {
                const uint64_t count = (b[need] & 0x7f) + 1;
                need += 1 + (b[need] & 0x80 ? pixelBytes : count * pixelBytes);
                pixels += count;
            }
        } else {
            need += uint64_t(w) * h * pixelBytes;
        }
    }
    if (need > b.size())
        throw UserError(path + ": image file is truncated (" + std::to_string(b.size()) +
                        " bytes, the header needs " + std::to_string(need) + ")");
}

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
    checkDeclaredSize(path, bytes, w, h);
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
        case FileFormat::Png:
            integer = true;
            return readPng(path, headerOnly);
        case FileFormat::Jpeg:
            integer = true;
            return readJpeg(path, headerOnly);
        case FileFormat::Pnm:
            integer = true;
            return readPnm(path, headerOnly);
        case FileFormat::Rgbe:
            return readRgbe(path, headerOnly);
        case FileFormat::Stb:
            break;
        case FileFormat::Unknown:
            throw UserError(path +
                            ": cannot read image: not a supported format (EXR, PNG, JPEG, "
                            "HDR, PFM, PPM/PGM, TGA, BMP, GIF, PSD)");
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
