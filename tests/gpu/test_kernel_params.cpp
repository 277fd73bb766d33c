// Parameters reach the GPU from their declaration (core/graph/KernelParams.h): standard values,
// declared parameters by name (enums as indices with generated defines), a uniform block for
// more than 128 bytes, and clear errors for members nothing sets and for buffer layouts that
// disagree with the declaration.
#include <gtest/gtest.h>

#include <stdexcept>

#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/graph/Renderer.h"
#include "tests/support/GpuSupport.h"

namespace loom {
namespace {

// A pass whose kernel is a parameter; it declares one parameter of each kind.
class KernelParamsProbePass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        r.outputTexture("output", gpu::Format::RGBA32F).doc("values the kernel saw");
        r.outputBuffer("values").bytesPerPixel(16, 16).optional().doc("header + vec4 per pixel");
        r.param("kernel", "").doc("GLSL file");
        r.param("count", 7).doc("int parameter");
        r.param("gain", 2.5).doc("float parameter");
        r.param("flag", true).doc("bool parameter");
        r.paramEnum("mode", "third", {"first", "secondChoice", "third"}).doc("pass-local enum");
        r.paramEnum("misHeuristic", "balance", shaderEnum("MIS_HEURISTIC")).doc("shared enum");
        r.paramVec("tint", {0.25, 0.5, 0.75}).doc("vec3 parameter");
        for (int i = 0; i < 40; ++i) {
            std::string name = std::to_string(i);
            name.insert(name.begin(), 'w');  // ("w" + s trips GCC 12's -Wrestrict false positive)
            r.param(name, double(i) + 0.5).doc("wide");
        }
    }
    void execute(ExecuteContext& ctx) override {
        auto pipeline = compileKernel(*this, ctx.shaders(), param<std::string>("kernel"));
        gpu::Bindings b;
        b.set("outputImage", ctx.texture("output"));
        if (ctx.has("values")) b.set("Values", ctx.buffer("values"));
        KernelParams p(*this, *pipeline, ctx);
        if (p.has("extra")) p.set("extra", 42u);
        p.dispatch(ctx, b, ctx.width(), ctx.height());
    }
};
LOOM_REGISTER_PASS(KernelParamsProbePass, "KernelParamsProbe", "test pass for KernelParams");

// A pass-local enum whose defines would shadow a registered shader enum's.
class KernelParamsCollisionPass : public KernelParamsProbePass {
public:
    void reflect(PassReflection& r) const override {
        r.outputTexture("output", gpu::Format::RGBA32F);
        r.param("kernel", "");
        r.paramEnum("misHeuristic", "balance", {"balance", "power"});
    }
};
LOOM_REGISTER_PASS(KernelParamsCollisionPass, "KernelParamsCollision", "test pass");

std::unique_ptr<Renderer> probe(const test::TempDir& dir, const std::string& kernel,
                                const std::string& type = "KernelParamsProbe",
                                bool values = false) {
    test::writeFile(dir / "k.comp", kernel);
    std::string outputs = values ? R"(["p.output", "p.values"])" : R"(["p.output"])";
    auto graph = RenderGraph::parse(R"({"passes": [{"name": "p", "type": ")" + type +
                                        R"(", "params": {"kernel": ")" + (dir / "k.comp") +
                                        R"("}}], "outputs": )" + outputs + "}",
                                    (dir / "g.json"));
    return std::make_unique<Renderer>(test::gpuContext(), std::move(graph), 2, 1, 5);
}

const char* kHeader = R"(#version 460
layout(local_size_x = 8, local_size_y = 1) in;
layout(rgba32f) uniform writeonly image2D outputImage;
)";

TEST(KernelParams, DeclaredParametersAndStandardValuesReachTheKernelByName) {
    test::TempDir dir("loom-kp");
    auto r = probe(dir, std::string(kHeader) + R"(
layout(push_constant) uniform Params {
    uvec2 frameSize; uint frameIndex; uint seed;
    int count; float gain; uint flag; uint mode; uint misHeuristic; vec3 tint; uint extra;
} pc;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(pc.frameSize.x)) return;
    // Generated defines name the choices of a pass-local enum and of a shared one.
    bool defines = MODE_FIRST == 0u && MODE_SECOND_CHOICE == 1u && MODE_THIRD == 2u &&
                   MIS_HEURISTIC_BALANCE == 0u && MIS_HEURISTIC_POWER == 1u;
    if (p.x == 0)
        imageStore(outputImage, p, vec4(float(pc.count), pc.gain, float(pc.flag),
                                        float(pc.mode) + (defines ? 10.0 : 0.0)));
    else
        imageStore(outputImage, p, vec4(pc.tint, float(pc.extra + pc.seed + 100u * pc.frameSize.x +
                                                       1000u * pc.misHeuristic)));
})");
    r->graph().findPass("p")->setParam("misHeuristic", "power");
    r->frame();
    ImageData img = r->readOutput("p.output");
    EXPECT_EQ(img.at(0, 0, 0), 7.0f);   // count
    EXPECT_EQ(img.at(0, 0, 1), 2.5f);   // gain
    EXPECT_EQ(img.at(0, 0, 2), 1.0f);   // flag
    EXPECT_EQ(img.at(0, 0, 3), 12.0f);  // mode = index 2, defines right
    EXPECT_EQ(img.at(1, 0, 0), 0.25f);
    EXPECT_EQ(img.at(1, 0, 2), 0.75f);
    EXPECT_EQ(img.at(1, 0, 3), float(42 + 5 + 200 + 1000));  // extra, seed, frameSize, power
}

TEST(KernelParams, UniformBlockCarriesMoreThanPushConstantsHold) {
    test::TempDir dir("loom-kp");
    std::string members, sum;
    for (int i = 0; i < 40; ++i) {
        members += "float w" + std::to_string(i) + "; ";
        sum += (i ? " + " : "") + std::string("p.w") + std::to_string(i);
    }
    // 40 floats + 2 ints = 168 bytes: beyond the 128 bytes push constants guarantee.
    auto r = probe(dir, std::string(kHeader) +
                            "layout(std140) uniform PassParams { uvec2 frameSize; " + members +
                            "} p;\nvoid main() {\n    ivec2 q = ivec2(gl_GlobalInvocationID.xy);\n"
                            "    if (q.x >= int(p.frameSize.x)) return;\n"
                            "    imageStore(outputImage, q, vec4(" +
                            sum + ", p.w0, p.w39, 0.0));\n}\n");
    r->graph().findPass("p")->setParam("w39", 100.0);
    r->frame();
    ImageData img = r->readOutput("p.output");
    // sum_{i<39} (i + 0.5) + 100 = 741 + 19.5 + 100
    EXPECT_EQ(img.at(1, 0, 0), 860.5f);
    EXPECT_EQ(img.at(1, 0, 1), 0.5f);
    EXPECT_EQ(img.at(1, 0, 2), 100.0f);
}

void expectError(Renderer& r, const std::string& expected) {
    try {
        r.frame();
        ADD_FAILURE() << "no error; expected: " << expected;
    } catch (const UserError& e) {
        EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
}

TEST(KernelParams, AMemberNothingSetsIsAnErrorNamingPassAndMember) {
    test::TempDir dir("loom-kp");
    // `gainn` drifted from the declared `gain`: it would read zero silently.
    auto r = probe(dir, std::string(kHeader) + R"(
layout(push_constant) uniform Params { uvec2 frameSize; float gainn; } pc;
void main() { imageStore(outputImage, ivec2(gl_GlobalInvocationID.xy), vec4(pc.gainn)); })");
    expectError(*r, "pass 'p', kernel '");
    expectError(*r, "parameter member(s) gainn are set by nothing");
}

TEST(KernelParams, AMemberOfAnotherTypeIsAnError) {
    test::TempDir dir("loom-kp");
    auto r = probe(dir, std::string(kHeader) + R"(
layout(push_constant) uniform Params { uvec2 frameSize; uint gain; } pc;
void main() { imageStore(outputImage, ivec2(gl_GlobalInvocationID.xy), vec4(pc.gain)); })");
    expectError(*r, "parameter member 'gain' is uint but is set as float");
}

TEST(KernelParams, BufferElementSizeIsCheckedAgainstTheSpirvStride) {
    const std::string body = R"(
layout(push_constant) uniform Params { uvec2 frameSize; } pc;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.frameSize.x) return;
    v[i].a = vec4(float(i));
    imageStore(outputImage, ivec2(i, 0), vec4(1.0));
})";
    {
        // Declared: 16 header bytes + 16 bytes per pixel, as the kernel reads it.
        test::TempDir dir("loom-kp");
        auto r = probe(
            dir,
            std::string(kHeader) +
                "struct E { vec4 a; };\nlayout(std430) buffer Values { vec4 header; E v[]; };" +
                body,
            "KernelParamsProbe", true);
        EXPECT_NO_THROW(r->frame());
    }
    {
        // The kernel's element grew to 32 bytes; the declaration did not follow.
        test::TempDir dir("loom-kp");
        auto r = probe(dir,
                       std::string(kHeader) +
                           "struct E { vec4 a; vec4 b; };\nlayout(std430) buffer Values { vec4 "
                           "header; E v[]; };" +
                           body,
                       "KernelParamsProbe", true);
        expectError(*r, "port 'values' declares 16 header bytes + 16 bytes per pixel, but kernel");
        expectError(*r, "reads 'Values' as 16 header bytes + an array of 32-byte elements");
    }
}

TEST(KernelParams, PassEnumDefinesMayNotShadowSharedEnums) {
    test::TempDir dir("loom-kp");
    auto r = probe(dir, std::string(kHeader) + "void main() {}\n", "KernelParamsCollision");
    try {
        r->frame();
        ADD_FAILURE() << "no error for a colliding enum define";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("MIS_HEURISTIC_BALANCE"), std::string::npos)
            << e.what();
    }
}

TEST(KernelParams, EnumNamesInUpperSnakeCase) {
    EXPECT_EQ(upperSnakeCase("misHeuristic"), "MIS_HEURISTIC");
    EXPECT_EQ(upperSnakeCase("defensivePairwise"), "DEFENSIVE_PAIRWISE");
    EXPECT_EQ(upperSnakeCase("rgba32f"), "RGBA_32F");
    EXPECT_EQ(upperSnakeCase("aces"), "ACES");
    auto d = enumDefines("SHIFT", {"hybrid", "reconnection", "replay"});
    EXPECT_EQ(d.at("SHIFT_HYBRID"), "0u");
    EXPECT_EQ(d.at("SHIFT_REPLAY"), "2u");
}

}  // namespace
}  // namespace loom
