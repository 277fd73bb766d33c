// Passes on the GPU (lavapipe) against CPU implementations of the same formulas: a JSON-only
// ComputePass (box blur), ToneMap, Accumulate (mean, variance, resets), ErrorMetric, and
// determinism of seeded renders.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/graph/Renderer.h"
#include "core/image/Image.h"
#include "tests/support/GpuSupport.h"

namespace {

using loom::ImageData;
using loom::Renderer;
using loom::RenderGraph;
using loom::test::TempDir;

const std::string kData = LOOM_TEST_DATA;

std::unique_ptr<Renderer> makeRenderer(std::unique_ptr<RenderGraph> graph, uint32_t w, uint32_t h,
                                       uint32_t seed = 0) {
    return std::make_unique<Renderer>(loom::test::gpuContext(), std::move(graph), w, h, seed);
}

// Deterministic test pattern with HDR, tiny and negative values; alpha varies too.
ImageData pattern(uint32_t w, uint32_t h, float scale = 1.0f, uint32_t salt = 0) {
    ImageData img = ImageData::make(w, h, 4);
    uint32_t state = 12345u + salt * 7919u;
    for (auto& v : img.pixels) {
        state = state * 1664525u + 1013904223u;
        v = float(state >> 8) / 16777216.0f * scale;
    }
    return img;
}

// |gpu - cpu| <= tol + rel * |cpu| for every value; reports the first few mismatches.
void expectNear(const ImageData& gpu, const ImageData& cpu, double tol, const std::string& what,
                double rel = 0.0) {
    ASSERT_EQ(gpu.width, cpu.width) << what;
    ASSERT_EQ(gpu.height, cpu.height) << what;
    ASSERT_EQ(gpu.channels, cpu.channels) << what;
    int reported = 0;
    double worst = 0.0;  // in units of the allowed error
    for (size_t i = 0; i < gpu.pixels.size(); ++i) {
        double d = std::abs(double(gpu.pixels[i]) - double(cpu.pixels[i]));
        double allowed = tol + rel * std::abs(double(cpu.pixels[i]));
        worst = std::max(worst, allowed > 0 ? d / allowed : d > 0 ? INFINITY : 0.0);
        if (!(d <= allowed) && reported++ < 5) {
            size_t p = i / gpu.channels;
            ADD_FAILURE() << what << ": pixel (" << p % gpu.width << ", " << p / gpu.width
                          << ") channel " << i % gpu.channels << ": gpu " << gpu.pixels[i]
                          << " cpu " << cpu.pixels[i];
        }
    }
    EXPECT_LE(worst, 1.0) << what << ": worst error relative to the tolerance";
}

// ---------------------------------------------------------------------------------------------
// ComputePass from JSON with a kernel that exists only in tests/data

ImageData cpuBoxBlur(const ImageData& in, int r) {
    ImageData out = ImageData::make(in.width, in.height, 4);
    int w = int(in.width), h = int(in.height);
    float n = float((2 * r + 1) * (2 * r + 1));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (uint32_t c = 0; c < 4; ++c) {
                float sum = 0.0f;
                for (int dy = -r; dy <= r; ++dy)
                    for (int dx = -r; dx <= r; ++dx)
                        sum += in.at(std::clamp(x + dx, 0, w - 1), std::clamp(y + dy, 0, h - 1), c);
                out.at(x, y, c) = sum / n;
            }
    return out;
}

TEST(PassesGpu, JsonComputePassBoxBlurMatchesCpu) {
    TempDir tmp("loom-passes");
    const uint32_t w = 13, h = 9;  // not multiples of the 8x8 workgroup
    ImageData input = pattern(w, h);
    loom::writeImage(tmp / "input.exr", input);

    auto graph = RenderGraph::load(kData + "/box_blur.json");
    graph->setParam("src.path", tmp / "input.exr");
    auto r = makeRenderer(std::move(graph), w, h);
    for (int radius : {0, 1, 3}) {
        r->graph().setParam("blur.radius", radius);
        r->frame();
        ImageData out = r->readOutput("blur.output");
        if (radius == 0) {
            expectNear(out, input, 0.0, "radius 0 is the identity");
        }
        // Same summation order; only the final division may round differently.
        expectNear(out, cpuBoxBlur(input, radius), 1e-6, "radius " + std::to_string(radius));
    }
    // The blur must actually blur: radius 3 differs from the input.
    EXPECT_GT(std::abs(r->readOutput("blur.output").at(6, 4, 0) - input.at(6, 4, 0)), 1e-3f);
    EXPECT_EQ(r->gpu().validationErrors(), 0u);
}

TEST(PassesGpu, ComputePassConstantsDefinesAndDispatch) {
    auto graph = RenderGraph::parse(R"({
      "passes": [{"name": "k", "type": "ComputePass", "params": {
        "shader": "constants.comp",
        "outputs": {"values": {"glsl": "Values", "kind": "buffer", "bytes": 256},
                    "mask": {"glsl": "maskImage", "format": "r32f", "optional": true}},
        "constants": {
          "gain": {"type": "float", "default": 1.0},
          "radius": {"type": "int", "default": 0},
          "samples": {"type": "uint", "default": 1},
          "flip": {"type": "bool", "default": false},
          "offset": {"type": "vec2"},
          "tint": {"type": "vec3"},
          "afterTint": {"type": "float"},
          "plane": {"type": "vec4"}},
        "defines": {"SCALE_DEFINE": 2.5},
        "dispatch": [3],
        "gain": 2.75, "radius": -4, "samples": 9, "flip": true, "offset": [0.5, -1.5],
        "tint": [0.125, 0.25, 0.375], "afterTint": 6.5, "plane": [1, -2, 3, -4]}}],
      "outputs": ["k.values"]})",
                                    kData + "/constants_graph.json");
    auto r = makeRenderer(std::move(graph), 6, 5, 42);
    auto read = [&] {
        std::vector<float> v(64);
        r->gpu().downloadBuffer(*r->graph().outputBuffer("k.values"), v.data(), 256);
        return v;
    };
    r->frame();
    r->frame();
    std::vector<float> v = read();
    const std::vector<float> expected{2.75f, -4, 9,  1, 0.5f, -1.5f, 0.125f, 0.25f, 0.375f, 6.5f, 1,
                                      -2,    3,  -4, 6, 5,    1,     42,     2.5f,  0,      3};
    for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(v[i], expected[i]) << "value " << i;
    // dispatch [3] runs exactly three threads.
    EXPECT_EQ(v[32], 1.0f);
    EXPECT_EQ(v[34], 3.0f);
    EXPECT_EQ(v[35], 0.0f);

    // A constant changes without a recompile; marking the optional output sets HAS_MASK.
    r->graph().setParam("k.gain", 0.25);
    r->graph().markOutput("k.mask");
    r->frame();
    v = read();
    EXPECT_EQ(v[0], 0.25f);
    EXPECT_EQ(v[19], 1.0f);
}

TEST(PassesGpu, ComputePassPersistentHistoryResets) {
    auto graph = RenderGraph::parse(R"({
      "passes": [{"name": "k", "type": "ComputePass", "params": {
        "shader": "frame_counter.comp",
        "outputs": {"output": {"glsl": "outputImage"}},
        "persistent": {"count": {"glsl": "countImage", "format": "r32f"}}}}],
      "outputs": ["k.output"]})",
                                    kData + "/counter_graph.json");
    auto r = makeRenderer(std::move(graph), 5, 3);
    auto expectCount = [&](float n, float reset, const char* what) {
        ImageData out = r->readOutput("k.output");
        for (uint32_t y = 0; y < r->height(); ++y)
            for (uint32_t x = 0; x < r->width(); ++x) {
                ASSERT_EQ(out.at(x, y, 0), n) << what << " at " << x << "," << y;
                ASSERT_EQ(out.at(x, y, 1), reset) << what << " at " << x << "," << y;
            }
    };
    r->frame();
    expectCount(1, 1, "first frame");
    r->frame();
    r->frame();
    expectCount(3, 0, "third frame");
    r->resize(4, 6);
    r->frame();
    expectCount(1, 1, "after resize");
    r->frame();
    expectCount(2, 0, "second frame after resize");
    r->graph().invalidate("test");
    r->frame();
    expectCount(1, 1, "after recompile");
}

TEST(PassesGpu, AliasedChainComputesTheSameValues) {
    std::string text = R"({"passes": [)";
    const char* names[] = {"A", "B", "C", "D"};
    for (int i = 0; i < 4; ++i)
        text += std::string(i ? "," : "") + R"({"name": ")" + names[i] +
                R"(", "type": "ComputePass", "params": {"shader": "add.comp",
          "inputs": {"input": {"glsl": "inputImage", "format": "rgba32f", "optional": true}},
          "outputs": {"output": {"glsl": "outputImage"}},
          "constants": {"step": {"type": "float"}}, "step": )" +
                std::to_string(1 << i) + "}}";
    text += R"(], "edges": [["A.output", "B.input"], ["B.output", "C.input"],
                            ["C.output", "D.input"]],
               "outputs": ["D.output"]})";
    auto r = makeRenderer(RenderGraph::parse(text, kData + "/chain_graph.json"), 9, 7);
    r->frame();
    const auto& cg = *r->graph().compiled();
    ASSERT_EQ(cg.physicalCount, 3);
    ASSERT_EQ(cg.resources[cg.portResource.at("A.output")].physical,
              cg.resources[cg.portResource.at("C.output")].physical);
    auto expectChain = [&](const std::string& port, float sum) {
        ImageData out = r->readOutput(port);
        ImageData cpu = ImageData::make(9, 7, 4);
        for (uint32_t y = 0; y < 7; ++y)
            for (uint32_t x = 0; x < 9; ++x) {
                cpu.at(x, y, 0) = float(x) + sum;
                cpu.at(x, y, 1) = float(y) + sum;
                cpu.at(x, y, 2) = cpu.at(x, y, 3) = sum;
            }
        expectNear(out, cpu, 0.0, port);
    };
    expectChain("D.output", 15);
    r->frame();  // the aliased memory is rewritten in the right order every frame
    expectChain("D.output", 15);
    r->graph().markOutput("B.output");
    r->frame();
    expectChain("B.output", 3);
    expectChain("D.output", 15);
}

// frame() must fail with a message naming the pass and `expected`.
void expectFrameError(const std::string& params, const std::string& expected) {
    auto graph = RenderGraph::parse(R"({"passes": [{"name": "k", "type": "ComputePass",
        "params": {"shader": "add.comp", )" +
                                        params + R"(}}], "outputs": ["k.output"]})",
                                    kData + "/error_graph.json");
    auto r = makeRenderer(std::move(graph), 4, 4);
    try {
        r->frame();
        ADD_FAILURE() << "no error for " << params;
    } catch (const loom::UserError& e) {
        std::string msg = e.what();
        EXPECT_EQ(msg.rfind("pass 'k' (ComputePass): ", 0), 0u) << msg;
        EXPECT_NE(msg.find(expected), std::string::npos) << msg;
    }
}

TEST(PassesGpu, ComputePassInterfaceErrorsNameThePort) {
    const std::string input =
        R"("inputs": {"input": {"glsl": "inputImage", "format": "rgba32f", "optional": true}}, )";
    expectFrameError(input + R"("outputs": {"output": {"glsl": "resultImage"}})",
                     "port 'output': the shader declares no resource 'resultImage'; it "
                     "declares: inputImage, outputImage");
    expectFrameError(input + R"("outputs": {"output": {"glsl": "outputImage", "format": "r32f"}})",
                     "port 'output' is r32f but the shader declares 'outputImage' as rgba32f");
    expectFrameError(input + R"("outputs": {"output": {"glsl": "outputImage"}},
        "constants": {"strength": {"type": "float"}})",
                     "constant 'strength' is not a member of the shader's push_constant block");
    expectFrameError(input + R"("outputs": {"output": {"glsl": "outputImage"}},
        "constants": {"step": {"type": "int"}})",
                     "constant 'step' is declared int but the shader's push constant is float");
    expectFrameError(R"("shader": "missing_kernel.comp", "outputs": {"output": {}})",
                     "shader file 'missing_kernel.comp' not found");
}

TEST(PassesGpu, ShaderHotReloadThroughTheGraph) {
    TempDir tmp("loom-reload");
    auto kernel = [](const std::string& value) {
        return "#version 460\n"
               "layout(local_size_x = 8, local_size_y = 8) in;\n"
               "layout(rgba32f) uniform writeonly image2D outputImage;\n"
               "layout(push_constant) uniform Params { uvec2 frameSize; } pc;\n"
               "void main() {\n"
               "    ivec2 p = ivec2(gl_GlobalInvocationID.xy);\n"
               "    imageStore(outputImage, p, vec4(" +
               value + "));\n}\n";
    };
    loom::test::writeFile(tmp / "fill.comp", kernel("1.0"));
    loom::test::writeFile(tmp / "graph.json", R"({"passes": [{"name": "k", "type": "ComputePass",
      "params": {"shader": "fill.comp", "outputs": {"output": {"glsl": "outputImage"}}}}],
      "outputs": ["k.output"]})");
    auto r = makeRenderer(RenderGraph::load(tmp / "graph.json"), 4, 4);
    r->frame();
    EXPECT_EQ(r->readOutput("k.output").at(3, 3, 0), 1.0f);
    EXPECT_EQ(r->graph().reloadShaders(r->shaders()), 0u);

    loom::test::writeFile(tmp / "fill.comp", kernel("2.0"));
    EXPECT_EQ(r->graph().reloadShaders(r->shaders()), 1u);
    r->frame();
    EXPECT_EQ(r->readOutput("k.output").at(3, 3, 0), 2.0f);

    // A broken edit reports file:line and the line; the last good image stays readable.
    loom::test::writeFile(tmp / "fill.comp", kernel("undefined_value"));
    EXPECT_EQ(r->graph().reloadShaders(r->shaders()), 1u);
    try {
        r->frame();
        ADD_FAILURE() << "broken shader compiled";
    } catch (const loom::UserError& e) {
        std::string msg = e.what();
        EXPECT_EQ(msg.rfind("pass 'k' (ComputePass): ", 0), 0u) << msg;
        EXPECT_NE(msg.find(std::filesystem::weakly_canonical(tmp / "fill.comp").string() + ":7:"),
                  std::string::npos)
            << msg;
        EXPECT_NE(msg.find("imageStore(outputImage, p, vec4(undefined_value));"), std::string::npos)
            << msg;
    }
    EXPECT_EQ(r->readOutput("k.output").at(0, 0, 0), 2.0f);

    // Fixing the file is enough: the next frame compiles it.
    loom::test::writeFile(tmp / "fill.comp", kernel("3.0"));
    r->graph().reloadShaders(r->shaders());
    r->frame();
    EXPECT_EQ(r->readOutput("k.output").at(3, 3, 0), 3.0f);
}

// ---------------------------------------------------------------------------------------------
// ToneMap

float cpuToneMap(float c, float exposure, const std::string& op, bool srgb) {
    float v = c * std::exp2(exposure);
    if (op == "reinhard") {
        v = v / (1.0f + v);
    } else if (op == "aces") {
        // Narkowicz 2015.
        v = std::clamp((v * (2.51f * v + 0.03f)) / (v * (2.43f * v + 0.59f) + 0.14f), 0.0f, 1.0f);
    }
    v = std::clamp(v, 0.0f, 1.0f);
    if (srgb) v = v > 0.0031308f ? 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f : 12.92f * v;
    return v;
}

TEST(PassesGpu, ToneMapFormulasOnCpu) {
    // Anchors computed by hand, so the CPU reference itself is right.
    EXPECT_FLOAT_EQ(cpuToneMap(1.0f, 0.0f, "reinhard", false), 0.5f);
    EXPECT_FLOAT_EQ(cpuToneMap(1.0f, 0.0f, "aces", false), 2.54f / 3.16f);
    EXPECT_FLOAT_EQ(cpuToneMap(0.25f, 1.0f, "clamp", true), 0.7353569f);  // sRGB(0.5)
    EXPECT_FLOAT_EQ(cpuToneMap(0.001f, 0.0f, "clamp", true), 0.01292f);   // linear segment
    EXPECT_FLOAT_EQ(cpuToneMap(5.0f, -1.0f, "clamp", false), 1.0f);
}

TEST(PassesGpu, ToneMapMatchesCpu) {
    TempDir tmp("loom-passes");
    const uint32_t w = 8, h = 4;
    // Values across every branch: negative, zero, sRGB's linear segment, mid, > 1, very large.
    const float values[] = {-0.25f, 0.0f, 0.001f, 0.003f, 0.02f, 0.18f, 0.5f,   0.75f,
                            1.0f,   1.5f, 2.0f,   4.0f,   8.0f,  16.0f, 100.0f, 1e4f};
    ImageData input = ImageData::make(w, h, 4);
    for (size_t i = 0; i < input.pixels.size(); ++i) input.pixels[i] = values[(i * 5 + i / 7) % 16];
    loom::writeImage(tmp / "hdr.exr", input);

    auto graph = RenderGraph::parse(R"({
      "passes": [{"name": "src", "type": "ImageLoader"}, {"name": "tm", "type": "ToneMap"}],
      "edges": [["src.output", "tm.input"]],
      "outputs": ["tm.output"]})",
                                    tmp / "tonemap.json");
    graph->setParam("src.path", tmp / "hdr.exr");
    auto r = makeRenderer(std::move(graph), w, h);
    for (std::string op : {"clamp", "reinhard", "aces"})
        for (float exposure : {-1.5f, 0.0f, 2.0f})
            for (bool srgb : {false, true}) {
                r->graph().setParam("tm.operator", op);
                r->graph().setParam("tm.exposure", exposure);
                r->graph().setParam("tm.srgb", srgb);
                r->frame();
                ImageData out = r->readOutput("tm.output");
                ImageData expected = ImageData::make(w, h, 4, 1.0f);  // alpha is 1
                for (size_t p = 0; p < size_t(w) * h; ++p)
                    for (int c = 0; c < 3; ++c)
                        expected.pixels[p * 4 + c] =
                            cpuToneMap(input.pixels[p * 4 + c], exposure, op, srgb);
                // Float math on both sides; GPU pow/division may differ in the last bits.
                expectNear(
                    out, expected, 2e-6,
                    op + " exposure " + std::to_string(exposure) + (srgb ? " srgb" : " linear"));
            }
}

// ---------------------------------------------------------------------------------------------
// Accumulate

// What tests/data/frame_value.comp writes.
float frameValue(uint32_t f, uint32_t x, uint32_t y, uint32_t c, float offset) {
    float v = c == 0   ? float((f * 7u + x * 3u + y * 5u) % 11u)
              : c == 1 ? float(f % 4u) * 0.5f
              : c == 2 ? float((f * f + x) % 13u) * 0.25f
                       : 1.0f;
    return v + offset;
}

struct Expected {
    ImageData mean, variance;
};

// Mean and unbiased variance (a = frame count) over frames `frames` of frame_value.comp.
Expected cpuAccumulate(uint32_t w, uint32_t h, const std::vector<uint32_t>& frames, float offset) {
    Expected e{ImageData::make(w, h, 4), ImageData::make(w, h, 4)};
    double n = double(frames.size());
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            for (uint32_t c = 0; c < 4; ++c) {
                double sum = 0.0, sq = 0.0;
                for (uint32_t f : frames) sum += frameValue(f, x, y, c, offset);
                double mean = sum / n;
                for (uint32_t f : frames) sq += std::pow(frameValue(f, x, y, c, offset) - mean, 2);
                e.mean.at(x, y, c) = float(mean);
                e.variance.at(x, y, c) = c == 3 ? float(n) : n > 1 ? float(sq / (n - 1)) : 0.0f;
            }
    return e;
}

void expectAccumulated(Renderer& r, const std::vector<uint32_t>& frames, float offset,
                       const std::string& what) {
    Expected e = cpuAccumulate(r.width(), r.height(), frames, offset);
    // Welford in float over <= 10 frames of values <= ~25: error well below 1e-4.
    expectNear(r.readOutput("acc.output"), e.mean, 1e-4, what + " mean");
    ImageData var = r.readOutput("acc.variance");
    expectNear(var, e.variance, 1e-4, what + " variance");
    EXPECT_EQ(r.graph().findPass("acc")->stats().at("frames"), double(frames.size())) << what;
}

TEST(PassesGpu, AccumulateMeanVarianceAndResets) {
    auto r = makeRenderer(RenderGraph::load(kData + "/accumulate.json"), 11, 6);
    std::vector<uint32_t> frames;
    for (uint32_t f = 0; f < 6; ++f) {
        r->frame();
        frames.push_back(f);
    }
    expectAccumulated(*r, frames, 0.0f, "6 frames");
    // The variance is not trivially zero.
    EXPECT_GT(r->readOutput("acc.variance").at(3, 2, 0), 1.0f);

    // A parameter downstream of Accumulate does not reset it.
    r->graph().setParam("tm.exposure", 1.0);
    r->frame();
    frames.push_back(6);
    expectAccumulated(*r, frames, 0.0f, "after a downstream change");

    // An upstream parameter change restarts the mean at the next frame.
    r->graph().setParam("gen.offset", 10.0);
    r->frame();
    expectAccumulated(*r, {7}, 10.0f, "first frame after an upstream change");
    r->frame();
    r->frame();
    expectAccumulated(*r, {7, 8, 9}, 10.0f, "three frames after an upstream change");

    // Renderer::reset() (camera moved) restarts it too.
    r->reset();
    r->frame();
    r->frame();
    expectAccumulated(*r, {10, 11}, 10.0f, "after reset()");

    // A resize reallocates the persistent mean/m2: accumulation restarts at the new size.
    r->resize(7, 5);
    r->frame();
    expectAccumulated(*r, {12}, 10.0f, "first frame after resize");
    r->frame();
    expectAccumulated(*r, {12, 13}, 10.0f, "second frame after resize");
}

TEST(PassesGpu, AccumulateMaxFramesFreezesTheMean) {
    auto graph = RenderGraph::load(kData + "/accumulate.json");
    graph->setParam("acc.maxFrames", 3);
    auto r = makeRenderer(std::move(graph), 9, 4);
    for (int i = 0; i < 5; ++i) r->frame();
    Expected e = cpuAccumulate(9, 4, {0, 1, 2}, 0.0f);
    expectNear(r->readOutput("acc.output"), e.mean, 1e-4, "frozen mean");
    // The variance of the frozen frames is still reported (it used to go stale).
    expectNear(r->readOutput("acc.variance"), e.variance, 1e-4, "frozen variance");
    EXPECT_EQ(r->graph().findPass("acc")->stats().at("frames"), 3.0);

    // Disabled: the input passes through.
    r->graph().setParam("acc.enabled", false);
    r->frame();
    expectNear(r->readOutput("acc.output"), cpuAccumulate(9, 4, {5}, 0.0f).mean, 0.0,
               "pass-through");
}

// ---------------------------------------------------------------------------------------------
// ErrorMetric

TEST(PassesGpu, ErrorMetricMatchesCoreImage) {
    TempDir tmp("loom-passes");
    const uint32_t w = 11, h = 7;
    ImageData reference = pattern(w, h, 2.0f, 1);
    ImageData image = pattern(w, h, 2.0f, 2);
    for (size_t i = 0; i < reference.pixels.size(); i += 9) reference.pixels[i] = 0.0f;
    loom::writeImage(tmp / "image.exr", image);
    loom::writeImage(tmp / "reference.exr", reference);

    auto graph = RenderGraph::parse(R"({
      "passes": [{"name": "img", "type": "ImageLoader", "params": {"path": "image.exr"}},
                 {"name": "ref", "type": "ImageLoader", "params": {"path": "reference.exr"}},
                 {"name": "em", "type": "ErrorMetric"}],
      "edges": [["img.output", "em.image"], ["ref.output", "em.reference"]],
      "outputs": ["em.perPixel", "em.error"]})",
                                    tmp / "metric.json");
    auto r = makeRenderer(std::move(graph), w, h);
    for (loom::Metric m :
         {loom::Metric::MSE, loom::Metric::RelMSE, loom::Metric::RMSE, loom::Metric::MAPE})
        for (double eps : {1e-2, 0.5}) {
            std::string name = loom::metricName(m);
            std::string what = name + " eps " + std::to_string(eps);
            r->graph().setParam("em.metric", name);
            r->graph().setParam("em.epsilon", eps);
            r->graph().setParam("em.falseColorMax", 0.5);
            r->frame();
            double expected = loom::computeMetric(m, image, reference, eps);
            auto stats = r->graph().findPass("em")->stats();
            ASSERT_EQ(stats.count(name), 1u) << what;
            EXPECT_NEAR(stats.at(name), expected, 1e-5 * expected) << what;

            ImageData perPixel = r->readOutput("em.perPixel");
            ASSERT_EQ(perPixel.channels, 1u);
            ImageData cpu = ImageData::make(w, h, 1);
            for (size_t p = 0; p < size_t(w) * h; ++p)
                cpu.pixels[p] = float(
                    loom::pixelError(m, &image.pixels[p * 4], &reference.pixels[p * 4], 4, eps));
            // Single-precision division on the GPU vs double on the CPU.
            expectNear(perPixel, cpu, 1e-7, what + " perPixel", 1e-6);
            expectNear(r->readOutput("em.error"), loom::falseColor(cpu, 0.5f, true), 1e-5,
                       what + " false colour");
        }
    // RMSE is the square root of MSE.
    r->graph().setParam("em.metric", "mse");
    r->frame();
    double mse = r->graph().findPass("em")->stats().at("mse");
    r->graph().setParam("em.metric", "rmse");
    r->frame();
    EXPECT_NEAR(r->graph().findPass("em")->stats().at("rmse"), std::sqrt(mse), 1e-6);
}

TEST(PassesGpu, ErrorMetricZeroForIdenticalImages) {
    TempDir tmp("loom-passes");
    loom::writeImage(tmp / "a.exr", pattern(5, 3));
    auto graph = RenderGraph::parse(R"({
      "passes": [{"name": "a", "type": "ImageLoader", "params": {"path": "a.exr"}},
                 {"name": "em", "type": "ErrorMetric", "params": {"metric": "mse"}}],
      "edges": [["a.output", "em.image"], ["a.output", "em.reference"]],
      "outputs": ["em.perPixel"]})",
                                    tmp / "same.json");
    auto r = makeRenderer(std::move(graph), 5, 3);
    r->frame();
    EXPECT_EQ(r->graph().findPass("em")->stats().at("mse"), 0.0);

    // A frame of another size is an error, not a metric over pixels that do not exist.
    r->resize(8, 8);
    try {
        r->frame();
        ADD_FAILURE() << "metric computed over a frame larger than the images";
    } catch (const loom::UserError& e) {
        EXPECT_STREQ(e.what(),
                     "pass 'em' (ErrorMetric): image and reference are 5x3 but the "
                     "frame is 8x8; render at the images' size");
    }
}

// ---------------------------------------------------------------------------------------------
// Determinism

std::vector<float> renderHello(uint32_t seed, uint32_t frames, const std::string& port) {
    auto r =
        makeRenderer(RenderGraph::load(std::string(LOOM_SOURCE_DIR) + "/graphs/hello_compute.json"),
                     24, 16, seed);
    r->frames(frames);
    return r->readOutput(port).pixels;
}

TEST(PassesGpu, SameSeedSameBytesDifferentSeedDiffers) {
    for (const char* port : {"accum.output", "tm.output"}) {
        SCOPED_TRACE(port);
        auto a = renderHello(7, 2, port);
        auto b = renderHello(7, 2, port);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
        auto c = renderHello(8, 2, port);
        ASSERT_EQ(a.size(), c.size());
        size_t differing = 0;
        for (size_t i = 0; i < a.size(); ++i) differing += a[i] != c[i];
        EXPECT_GT(differing, a.size() / 10) << "seed has (almost) no effect";
    }
}

}  // namespace
