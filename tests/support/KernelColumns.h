#pragma once
// Test kernels over "columns": each column is one query (rows of vec4 inputs), written to an
// EXR, run through a ComputePass that reads inputImage and writes outputImage (one invocation
// per column), and read back. Used by the manifold tests (SMS walks, MNEE walks).
#include <algorithm>
#include <fstream>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/graph/RenderGraph.h"
#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "core/scene/SceneLoader.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/TestSupport.h"

namespace loom::test {

inline std::string sourcePath(const std::string& rel) {
    return std::string(LOOM_SOURCE_DIR) + "/" + rel;
}

// A scene from Loom JSON text, written into dir.
inline scene::Scene sceneFromJson(const std::string& text, const TempDir& dir,
                                  const std::string& name = "scene.json") {
    std::ofstream(dir / name) << text;
    return scene::loadScene(dir / name);
}

// Runs the test kernel `shader` (relative to the source tree; it reads inputImage and writes
// outputImage of the same size) on `input` against `scene` at frame time `time`.
inline ImageData runKernelImage(const scene::Scene& scene, const std::string& shader,
                                const ImageData& input, float time = 0.0f) {
    using nlohmann::json;
    TempDir dir("loom-kernel-image");
    writeImage(dir / "in.exr", input);
    json g = {{"passes",
               {{{"name", "in"}, {"type", "ImageLoader"}, {"params", {{"path", "in.exr"}}}},
                {{"name", "k"},
                 {"type", "ComputePass"},
                 {"params",
                  {{"shader", sourcePath(shader)},
                   {"inputs", {{"input", {{"glsl", "inputImage"}, {"format", "rgba32f"}}}}},
                   {"outputs", {{"output", {{"glsl", "outputImage"}}}}}}}}}},
              {"edges", json::array({json::array({"in.output", "k.input"})})},
              {"outputs", {"k.output"}}};
    Renderer r(gpuContext(), RenderGraph::parse(g.dump(), dir / "graph.json"), input.width,
               input.height);
    r.setScene(scene);
    r.setTime(time);
    r.frame();
    return r.readOutput("k.output");
}

// Runs `shader` over the columns `in` against `scene` at frame time `time` (runKernelImage);
// returns outRows vec4 rows per column.
inline std::vector<std::vector<glm::vec4>> runColumns(const scene::Scene& scene,
                                                      const std::string& shader,
                                                      const std::vector<std::vector<glm::vec4>>& in,
                                                      uint32_t outRows, float time = 0.0f) {
    // The output has the input's size: enough rows for both.
    uint32_t n = uint32_t(in.size()), rows = outRows;
    for (const auto& c : in) rows = std::max(rows, uint32_t(c.size()));
    ImageData img;
    img.width = n;
    img.height = rows;
    img.channels = 4;
    img.pixels.assign(size_t(n) * rows * 4, 0.0f);
    for (uint32_t i = 0; i < n; ++i)
        for (uint32_t row = 0; row < in[i].size(); ++row)
            for (int c = 0; c < 4; ++c) img.pixels[(size_t(row) * n + i) * 4 + c] = in[i][row][c];
    ImageData out = runKernelImage(scene, shader, img, time);
    std::vector<std::vector<glm::vec4>> res(n, std::vector<glm::vec4>(outRows));
    for (uint32_t i = 0; i < n; ++i)
        for (uint32_t row = 0; row < outRows; ++row) {
            const float* p = &out.pixels[(size_t(row) * n + i) * out.channels];
            res[i][row] = glm::vec4(p[0], p[1], p[2], p[3]);
        }
    return res;
}

}  // namespace loom::test
