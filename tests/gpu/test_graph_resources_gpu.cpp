// Graph resources on the GPU: ComputePass outputs declared "inPlaceOf" an input write the
// input's buffer itself (chained twice here); a pass that reads the value before the writes
// runs first although it is declared later, and a previous-frame input of the overwritten
// value gets the value as produced, not as modified in place.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "tests/support/GpuSupport.h"

namespace {

using loom::ImageData;
using loom::Renderer;
using loom::RenderGraph;

const std::string kData = LOOM_TEST_DATA;

// What feedback_gen.comp writes for element i in a frame.
float value(uint64_t frame, uint32_t i) {
    return float(frame) * 1000.0f + float(i);
}

const char* kInPlaceGraph = R"({
  "passes": [
    {"name": "gen", "type": "ComputePass", "params": {
      "shader": "feedback_gen.comp",
      "outputs": {"values": {"glsl": "Values", "kind": "buffer", "bytesPerPixel": 4}},
      "dispatch": "values"}},
    {"name": "inc1", "type": "ComputePass", "params": {
      "shader": "increment_in_place.comp",
      "inputs": {"data": {"glsl": "Data", "kind": "buffer"}},
      "outputs": {"dataOut": {"glsl": "Data", "kind": "buffer", "bytesPerPixel": 4,
                              "inPlaceOf": "data"}},
      "dispatch": "dataOut"}},
    {"name": "inc2", "type": "ComputePass", "params": {
      "shader": "increment_in_place.comp",
      "inputs": {"data": {"glsl": "Data", "kind": "buffer"}},
      "outputs": {"dataOut": {"glsl": "Data", "kind": "buffer", "bytesPerPixel": 4,
                              "inPlaceOf": "data"}},
      "dispatch": "dataOut"}},
    {"name": "before", "type": "ComputePass", "params": {
      "shader": "feedback_lag.comp",
      "inputs": {"cur": {"glsl": "Cur", "kind": "buffer"},
                 "prev": {"glsl": "Prev", "kind": "buffer", "previousFrame": true}},
      "outputs": {"output": {"glsl": "outputImage"}}}},
    {"name": "after", "type": "ComputePass", "params": {
      "shader": "feedback_lag.comp",
      "inputs": {"cur": {"glsl": "Cur", "kind": "buffer"},
                 "prev": {"glsl": "Prev", "kind": "buffer", "previousFrame": true}},
      "outputs": {"output": {"glsl": "outputImage"}}}}],
  "edges": [["gen.values", "inc1.data"], ["inc1.dataOut", "inc2.data"],
            ["gen.values", "before.cur"], ["gen.values", "before.prev"],
            ["inc2.dataOut", "after.cur"], ["inc2.dataOut", "after.prev"]],
  "outputs": ["before.output", "after.output"]})";

TEST(GraphResourcesGpu, InPlaceIncrementsChainOnOneBuffer) {
    auto r = std::make_unique<Renderer>(
        loom::test::gpuContext(), RenderGraph::parse(kInPlaceGraph, kData + "/inplace.json"), 4, 4);
    auto expectFrame = [&](bool reset, const char* what) {
        uint64_t frame = r->graph().frameIndex() - 1;
        ImageData before = r->readOutput("before.output");
        ImageData after = r->readOutput("after.output");
        for (uint32_t y = 0; y < 4; ++y)
            for (uint32_t x = 0; x < 4; ++x) {
                SCOPED_TRACE(std::string(what) + " at " + std::to_string(x) + "," +
                             std::to_string(y));
                uint32_t i = y * 4 + x;
                // "before" reads gen.values before inc1 overwrites it, and its history copy
                // holds last frame's value as gen wrote it.
                ASSERT_EQ(before.at(x, y, 0), value(frame, i));
                ASSERT_EQ(before.at(x, y, 1), reset ? -1.0f : value(frame - 1, i));
                // Two in-place increments on the same memory.
                ASSERT_EQ(after.at(x, y, 0), value(frame, i) + 2.0f);
                ASSERT_EQ(after.at(x, y, 1), reset ? -1.0f : value(frame - 1, i) + 2.0f);
            }
    };
    r->frame();
    expectFrame(true, "first frame");
    r->frame();
    expectFrame(false, "second frame");
    r->frame();
    expectFrame(false, "third frame");

    // One buffer for gen.values and both in-place outputs; "before" was ordered first.
    const auto& cg = *r->graph().compiled();
    int ri = cg.portResource.at("gen.values");
    EXPECT_EQ(cg.portResource.at("inc1.dataOut"), ri);
    EXPECT_EQ(cg.portResource.at("inc2.dataOut"), ri);
    EXPECT_EQ(cg.resources[ri].inPlaceWriters,
              (std::vector<std::string>{"inc1.dataOut", "inc2.dataOut"}));
    std::vector<std::string> order;
    for (int pi : cg.order) order.push_back(r->graph().passes()[pi]->name());
    auto at = [&](const std::string& n) { return std::find(order.begin(), order.end(), n); };
    EXPECT_LT(at("before"), at("inc1"));
    EXPECT_LT(at("inc1"), at("inc2"));
}

}  // namespace

namespace {

// Context::uploadImageRows (moving shapes update the rows of the scene's vertex image that
// changed): those rows take the new texels, the others keep theirs; rows past the image throw.
TEST(GpuContext, UploadImageRowsReplacesOnlyThoseRows) {
    auto gpu = loom::test::gpuContext();
    const uint32_t w = 5, h = 4;
    auto image = gpu->createImage(w, h, loom::gpu::Format::RGBA32UI, "rows");
    std::vector<uint32_t> texels(size_t(w) * h * 4);
    for (size_t i = 0; i < texels.size(); ++i) texels[i] = uint32_t(i);
    gpu->uploadImage(*image, texels.data());
    std::vector<uint32_t> rows(size_t(w) * 2 * 4);
    for (size_t i = 0; i < rows.size(); ++i) rows[i] = 100000u + uint32_t(i);
    gpu->uploadImageRows(*image, rows.data(), 1, 2);
    std::vector<uint32_t> back(texels.size());
    gpu->downloadImage(*image, back.data());
    const size_t row = size_t(w) * 4;
    for (size_t i = 0; i < back.size(); ++i) {
        const bool updated = i >= row && i < 3 * row;
        ASSERT_EQ(back[i], updated ? rows[i - row] : texels[i]) << "word " << i;
    }
    EXPECT_THROW(gpu->uploadImageRows(*image, rows.data(), 3, 2), loom::GpuError);
    EXPECT_EQ(gpu->validationErrors(), 0u);
}

}  // namespace
