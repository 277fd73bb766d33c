// @FAMILY@ family tests: @PASS@ against the same formula on the CPU.
#include <gtest/gtest.h>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "tests/support/GpuSupport.h"

namespace loom {
namespace {

ImageData renderWith(const std::string& mode, double gain, const ImageData& input) {
    test::TempDir dir("loom-@KERNEL@");
    writeImage(dir / "input.exr", input);
    auto graph = RenderGraph::parse(R"({"passes": [
        {"name": "in", "type": "ImageLoader", "params": {"path": "input.exr"}},
        {"name": "p", "type": "@PASS@", "params": {"mode": ")" + mode + R"(", "gain": )" +
                                        std::to_string(gain) + R"(}}],
      "edges": [["in.output", "p.input"]], "outputs": ["p.output"]})",
                                    dir / "graph.json");
    Renderer r(test::gpuContext(), std::move(graph), input.width, input.height);
    r.frame();
    return r.readOutput("p.output");
}

TEST(@PASS@, MatchesTheFormulaOnTheCpu) {
    ImageData input = ImageData::make(8, 4, 4);
    for (size_t i = 0; i < input.pixels.size(); ++i) input.pixels[i] = 0.125f * float(i % 13);
    for (std::string mode : {"scale", "square"}) {
        ImageData out = renderWith(mode, 3.0, input);
        for (size_t i = 0; i < input.pixels.size(); ++i) {
            float v = input.pixels[i];
            float expected = 3.0f * (mode == "square" ? v * v : v);
            ASSERT_FLOAT_EQ(out.pixels[i], expected) << mode << " value " << i;
        }
    }
}

}  // namespace
}  // namespace loom
