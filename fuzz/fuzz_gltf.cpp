// Scene loader for .gltf files, through loadScene() and its range checks.
#include "core/scene/SceneLoader.h"
#include "fuzz/FuzzSupport.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string path = loom::fuzz::writeInput(nullptr, 0, ".gltf");
    return loom::fuzz::guard([&] {
        loom::fuzz::writeInput(data, size, ".gltf");
        loom::scene::loadScene(path);
    });
}
