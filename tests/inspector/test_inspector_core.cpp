// Core additions the inspector relies on, on lavapipe without a window: shader hot reload that
// keeps the last good version, swapping graphs in a Renderer, and turning memory aliasing off
// so every intermediate port stays readable.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "tests/support/GpuSupport.h"

namespace {

using loom::Renderer;
using loom::RenderGraph;
using loom::test::TempDir;
using loom::test::writeFile;

std::string shaderWriting(const std::string& value) {
    return "#version 460\n"
           "layout(local_size_x = 8, local_size_y = 8) in;\n"
           "layout(rgba32f) uniform writeonly image2D outputImage;\n"
           "void main() { imageStore(outputImage, ivec2(gl_GlobalInvocationID.xy), vec4(" +
           value + ")); }\n";
}

const char* kGraph = R"({"name": "reload", "passes": [
  {"name": "gen", "type": "ComputePass", "params": {"shader": "value.comp",
     "outputs": {"output": {"glsl": "outputImage", "format": "rgba32f"}}}}],
  "outputs": ["gen.output"]})";

float firstValue(Renderer& r) {
    return r.readOutput("gen.output").pixels[0];
}

// The cache key hashes file contents, so rewriting is enough; the short sleep keeps mtimes
// apart on coarse file systems anyway.
void rewrite(const std::string& path, const std::string& text) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    writeFile(path, text);
}

TEST(InspectorCore, ShaderReloadKeepsLastGoodVersion) {
    TempDir dir("loom-inspector-reload");
    writeFile(dir / "value.comp", shaderWriting("1.0"));
    writeFile(dir / "graph.json", kGraph);
    Renderer r(loom::test::gpuContext(), RenderGraph::load(dir / "graph.json"), 8, 8, 0,
               dir / "cache");
    r.shaders().setKeepLastGood(true);
    r.frame();
    EXPECT_EQ(firstValue(r), 1.0f);

    // A compile error: the frame still runs, with the last good pipeline; the error is kept.
    rewrite(dir / "value.comp", shaderWriting("1.0 +"));
    EXPECT_GT(r.graph().reloadShaders(r.shaders()), 0u);
    EXPECT_NO_THROW(r.frame());
    EXPECT_EQ(firstValue(r), 1.0f);
    auto errors = r.shaders().takeErrors();
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find("value.comp"), std::string::npos) << errors[0];
    EXPECT_TRUE(r.shaders().takeErrors().empty());

    // Fixed on disk: noticed although the broken version never entered the compiler's cache.
    rewrite(dir / "value.comp", shaderWriting("2.0"));
    EXPECT_GT(r.graph().reloadShaders(r.shaders()), 0u);
    r.frame();
    EXPECT_EQ(firstValue(r), 2.0f);
    EXPECT_TRUE(r.shaders().takeErrors().empty());
    EXPECT_EQ(r.graph().reloadShaders(r.shaders()), 0u);  // nothing changed since
}

TEST(InspectorCore, ShaderReloadWithoutKeepLastGoodThrows) {
    TempDir dir("loom-inspector-reload");
    writeFile(dir / "value.comp", shaderWriting("1.0"));
    writeFile(dir / "graph.json", kGraph);
    Renderer r(loom::test::gpuContext(), RenderGraph::load(dir / "graph.json"), 8, 8, 0,
               dir / "cache");
    r.frame();
    rewrite(dir / "value.comp", shaderWriting("oops"));
    EXPECT_GT(r.graph().reloadShaders(r.shaders()), 0u);
    EXPECT_THROW(r.frame(), loom::UserError);
}

TEST(InspectorCore, RendererSwapsGraphs) {
    TempDir dir("loom-inspector-reload");
    writeFile(dir / "value.comp", shaderWriting("3.0"));
    writeFile(dir / "graph.json", kGraph);
    writeFile(dir / "other.comp", shaderWriting("5.0"));
    std::string other = kGraph;
    other.replace(other.find("value.comp"), 10, "other.comp");
    writeFile(dir / "other.json", other);
    Renderer r(loom::test::gpuContext(), RenderGraph::load(dir / "graph.json"), 8, 8, 0,
               dir / "cache");
    r.frame();
    EXPECT_EQ(firstValue(r), 3.0f);
    auto old = r.setGraph(RenderGraph::load(dir / "other.json"));
    r.frame();
    EXPECT_EQ(firstValue(r), 5.0f);
    r.setGraph(std::move(old));  // swap back, as the inspector does when a new graph fails
    r.frame();
    EXPECT_EQ(firstValue(r), 3.0f);
}

TEST(InspectorCore, AliasingOffKeepsIntermediatesApart) {
    // a -> b -> c -> d: a.output and c.output have disjoint lifetimes and equal descriptions.
    auto g = RenderGraph::parse(R"({"passes": [
        {"name": "src", "type": "ComputePass", "params": {"shader": "x.comp",
           "outputs": {"output": {"glsl": "outputImage"}}}},
        {"name": "a", "type": "ToneMap"}, {"name": "b", "type": "ToneMap"},
        {"name": "c", "type": "ToneMap"}, {"name": "d", "type": "ToneMap"}],
      "edges": [["src.output", "a.input"], ["a.output", "b.input"], ["b.output", "c.input"],
                ["c.output", "d.input"]],
      "outputs": ["d.output"]})",
                                "alias.json");
    auto physical = [](const loom::CompiledGraph& cg, const std::string& port) {
        return cg.resources[cg.portResource.at(port)].physical;
    };
    auto on = g->compile(16, 16);
    EXPECT_EQ(physical(on, "a.output"), physical(on, "c.output"));
    EXPECT_TRUE(g->aliasing());
    g->setAliasing(false);
    auto off = g->compile(16, 16);
    EXPECT_EQ(off.physicalCount, int(off.resources.size()));
    EXPECT_NE(physical(off, "a.output"), physical(off, "c.output"));
}

}  // namespace
