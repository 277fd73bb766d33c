// The fuzz build (LOOM_FUZZ) compiles stb_image and stb_image_write from Debian's libstb-dev
// headers instead of linking libstb.so, so that the sanitizers and libFuzzer's coverage
// instrument the decoders too.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image.h>
#include <stb_image_write.h>
