// Previous-frame inputs on the GPU: a ComputePass input declared "previousFrame": true holds
// exactly what the connected output held at the end of the last frame (texture and buffer
// history copies), and the pass sees historyReset on the first frame, after Renderer::reset()
// and after a resize, until the history copy holds a frame again.
#include <gtest/gtest.h>

#include <string>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "tests/support/GpuSupport.h"

namespace {

using loom::ImageData;
using loom::Renderer;
using loom::RenderGraph;

const std::string kData = LOOM_TEST_DATA;

std::unique_ptr<Renderer> makeRenderer(const std::string& text, const std::string& file, uint32_t w,
                                       uint32_t h) {
    return std::make_unique<Renderer>(loom::test::gpuContext(),
                                      RenderGraph::parse(text, kData + "/" + file), w, h);
}

// What feedback_counter.comp / feedback_gen.comp write for a pixel or element in a frame.
float stamp(uint64_t frame, uint32_t x, uint32_t y) {
    return float(frame) * 1000.0f + float(x) + 100.0f * float(y);
}
float value(uint64_t frame, uint32_t i) {
    return float(frame) * 1000.0f + float(i);
}

TEST(GraphFeedbackGpu, SelfEdgeTextureHoldsLastFramesValue) {
    auto r = makeRenderer(R"({
      "passes": [{"name": "k", "type": "ComputePass", "params": {
        "shader": "feedback_counter.comp",
        "inputs": {"prev": {"glsl": "prevImage", "format": "rgba32f", "previousFrame": true}},
        "outputs": {"output": {"glsl": "outputImage"}}}}],
      "edges": [["k.output", "k.prev"]],
      "outputs": ["k.output"]})",
                          "feedback_counter_graph.json", 5, 3);
    // count: frames since the history was reset; lastStamp: what the previous frame wrote
    // (-1 = nothing: historyReset was set).
    auto expectFrame = [&](float count, bool reset, const char* what) {
        uint64_t frame = r->graph().frameIndex() - 1;
        ImageData out = r->readOutput("k.output");
        for (uint32_t y = 0; y < r->height(); ++y)
            for (uint32_t x = 0; x < r->width(); ++x) {
                SCOPED_TRACE(std::string(what) + " at " + std::to_string(x) + "," +
                             std::to_string(y));
                ASSERT_EQ(out.at(x, y, 0), count);
                ASSERT_EQ(out.at(x, y, 1), reset ? 1.0f : 0.0f);
                ASSERT_EQ(out.at(x, y, 2), stamp(frame, x, y));
                ASSERT_EQ(out.at(x, y, 3), reset ? -1.0f : stamp(frame - 1, x, y));
            }
    };
    r->frame();
    expectFrame(1, true, "first frame");
    r->frame();
    expectFrame(2, false, "second frame");
    r->frame();
    expectFrame(3, false, "third frame");
    r->reset();
    r->frame();
    expectFrame(1, true, "first frame after reset()");
    r->frame();
    expectFrame(2, false, "second frame after reset()");
    r->resize(4, 6);
    r->frame();
    expectFrame(1, true, "first frame after resize");
    r->frame();
    expectFrame(2, false, "second frame after resize");
}

TEST(GraphFeedbackGpu, BufferInputAndPreviousFrameInputFromOneOutput) {
    // lag is declared before gen but runs after it: only the ordinary edge orders them.
    auto r = makeRenderer(R"({
      "passes": [
        {"name": "lag", "type": "ComputePass", "params": {
          "shader": "feedback_lag.comp",
          "inputs": {"cur": {"glsl": "Cur", "kind": "buffer"},
                     "prev": {"glsl": "Prev", "kind": "buffer", "previousFrame": true}},
          "outputs": {"output": {"glsl": "outputImage"}}}},
        {"name": "gen", "type": "ComputePass", "params": {
          "shader": "feedback_gen.comp",
          "outputs": {"values": {"glsl": "Values", "kind": "buffer", "bytesPerPixel": 4}},
          "dispatch": "values"}}],
      "edges": [["gen.values", "lag.cur"], ["gen.values", "lag.prev"]],
      "outputs": ["lag.output"]})",
                          "feedback_lag_graph.json", 4, 4);
    auto expectFrame = [&](bool reset, const char* what) {
        uint64_t frame = r->graph().frameIndex() - 1;
        ImageData out = r->readOutput("lag.output");
        for (uint32_t y = 0; y < 4; ++y)
            for (uint32_t x = 0; x < 4; ++x) {
                SCOPED_TRACE(std::string(what) + " at " + std::to_string(x) + "," +
                             std::to_string(y));
                uint32_t i = y * 4 + x;
                ASSERT_EQ(out.at(x, y, 0), value(frame, i));
                ASSERT_EQ(out.at(x, y, 1), reset ? -1.0f : value(frame - 1, i));
                ASSERT_EQ(out.at(x, y, 2), reset ? 1.0f : 0.0f);
            }
    };
    r->frame();
    expectFrame(true, "first frame");
    r->frame();
    expectFrame(false, "second frame");
    r->frame();
    expectFrame(false, "third frame");
    r->reset();
    r->frame();
    expectFrame(true, "first frame after reset()");
    r->frame();
    expectFrame(false, "second frame after reset()");
    const auto& cg = *r->graph().compiled();
    EXPECT_EQ(cg.resources[cg.portResource.at("lag.prev")].name, "gen.values@prev");
}

}  // namespace
