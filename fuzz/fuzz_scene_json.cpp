// Scene loader for .json files, through loadScene() and its range checks.
#include "core/scene/SceneLoader.h"
#include "fuzz/FuzzSupport.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string path = loom::fuzz::writeInput(nullptr, 0, ".json");
    return loom::fuzz::guard([&] {
        loom::fuzz::writeInput(data, size, ".json");
        loom::scene::loadScene(path);
    });
}
