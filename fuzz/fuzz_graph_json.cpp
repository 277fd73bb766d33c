// Graph JSON: parse, validate and compile (cull, order, allocate plan), as loom validate does
// before it starts a device.
#include "core/graph/RenderGraph.h"
#include "fuzz/FuzzSupport.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    return loom::fuzz::guard([&] {
        auto g = loom::RenderGraph::parse(std::string(reinterpret_cast<const char*>(data), size),
                                          "fuzz.json");
        g->compile(64, 64);
    });
}
