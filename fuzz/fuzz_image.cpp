// Image files (core/image/ImageFile.cpp): the magic-byte dispatch, OpenEXR, PFM and stb_image
// (compiled from Debian's header in the fuzz build, so that ASan and coverage see inside it).
#include "core/image/Image.h"
#include "fuzz/FuzzSupport.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string path = loom::fuzz::writeInput(nullptr, 0, ".img");
    return loom::fuzz::guard([&] {
        loom::fuzz::writeInput(data, size, ".img");
        uint32_t w = 0, h = 0;
        loom::readImageSize(path, w, h);
        loom::ImageData img = loom::readImage(path, true);
        if (img.width != w || img.height != h || img.pixels.size() != size_t(w) * h * img.channels)
            __builtin_trap();  // the header and the decoded image must agree
    });
}
