#include "core/shader/SpirvReflect.h"

#include <gtest/gtest.h>

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>

#include <random>
#include <set>
#include <stdexcept>
#include <string>

namespace {

using loom::DescriptorKind;
using loom::reflectSpirv;

// glslang needs process-wide initialisation exactly once.
class GlslangEnvironment : public ::testing::Environment {
public:
    void SetUp() override { glslang::InitializeProcess(); }
    void TearDown() override { glslang::FinalizeProcess(); }
};

[[maybe_unused]] ::testing::Environment* const gGlslangEnv =
    ::testing::AddGlobalTestEnvironment(new GlslangEnvironment);

std::vector<uint32_t> compileCompute(
    const char* source,
    glslang::EShTargetLanguageVersion spirvVersion = glslang::EShTargetSpv_1_5) {
    // The shader must outlive the program that links it.
    glslang::TShader shader(EShLangCompute);
    shader.setStrings(&source, 1);
    shader.setEnvInput(glslang::EShSourceGlsl, EShLangCompute, glslang::EShClientVulkan, 100);
    shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_2);
    shader.setEnvTarget(glslang::EShTargetSpv, spirvVersion);
    shader.setAutoMapBindings(true);
    shader.setAutoMapLocations(true);
    const auto messages = static_cast<EShMessages>(EShMsgSpvRules | EShMsgVulkanRules);
    if (!shader.parse(GetDefaultResources(), 450, false, messages)) {
        ADD_FAILURE() << "GLSL parse failed:\n" << shader.getInfoLog();
        return {};
    }
    glslang::TProgram program;
    program.addShader(&shader);
    if (!program.link(messages) || !program.mapIO()) {
        ADD_FAILURE() << "GLSL link failed:\n" << program.getInfoLog();
        return {};
    }
    std::vector<unsigned int> spirv;
    glslang::GlslangToSpv(*program.getIntermediate(EShLangCompute), spirv);
    return {spirv.begin(), spirv.end()};
}

// Packs a string literal the way SPIR-V stores it (nul-terminated, little-endian words).
void appendString(std::vector<uint32_t>& words, const std::string& s) {
    std::vector<uint32_t> packed((s.size() + 4) / 4, 0u);
    for (size_t i = 0; i < s.size(); ++i) {
        packed[i / 4] |= static_cast<uint32_t>(static_cast<unsigned char>(s[i])) << (8 * (i % 4));
    }
    words.insert(words.end(), packed.begin(), packed.end());
}

uint32_t opWord(uint32_t opcode, size_t wordCount) {
    return (static_cast<uint32_t>(wordCount) << 16) | opcode;
}

std::vector<uint32_t> header() {
    return {0x07230203u, 0x00010500u, 0u, 100u, 0u};
}

void expectThrowContaining(const std::vector<uint32_t>& words, const std::string& fragment) {
    try {
        (void)reflectSpirv(words);
        ADD_FAILURE() << "expected std::runtime_error containing '" << fragment << "'";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
}

const char* kMainShader = R"(#version 450
layout(local_size_x = 8, local_size_y = 8) in;

layout(rgba32f) uniform image2D outImg;
layout(std430) readonly buffer Input { float data[]; } inBuf;
layout(std140) uniform Params { mat4 transform; vec4 tint; } params;
layout(push_constant) uniform Push {
    float scale;
    int mode;
    uvec2 extent;
    vec4 color;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.extent))) return;
    float v = inBuf.data[p.y * int(pc.extent.x) + p.x] * pc.scale + float(pc.mode);
    imageStore(outImg, p, params.transform * (pc.color * v) + params.tint);
}
)";

TEST(SpirvReflect, MainShaderBindings) {
    const auto words = compileCompute(kMainShader);
    ASSERT_FALSE(words.empty());
    const loom::ShaderReflection r = reflectSpirv(words);

    ASSERT_EQ(r.bindings.size(), 3u);
    std::set<uint32_t> bindingSlots;
    for (size_t i = 0; i < r.bindings.size(); ++i) {
        EXPECT_EQ(r.bindings[i].set, 0u);
        EXPECT_EQ(r.bindings[i].arraySize, 1u);
        bindingSlots.insert(r.bindings[i].binding);
        if (i > 0) {
            EXPECT_LT(r.bindings[i - 1].binding, r.bindings[i].binding)
                << "bindings must be sorted";
        }
    }
    EXPECT_EQ(bindingSlots, (std::set<uint32_t>{0, 1, 2}))
        << "auto-mapped bindings must be distinct and dense";

    const loom::ReflectedBinding* img = r.find("outImg");
    ASSERT_NE(img, nullptr);
    EXPECT_EQ(img->name, "outImg");
    EXPECT_EQ(img->blockName, "");
    EXPECT_EQ(img->kind, DescriptorKind::StorageImage);
    EXPECT_EQ(img->imageFormat, "rgba32f");
    EXPECT_FALSE(img->readonly);

    const loom::ReflectedBinding* in = r.find("inBuf");
    ASSERT_NE(in, nullptr);
    EXPECT_EQ(in, r.find("Input")) << "lookup by block name must find the same binding";
    EXPECT_EQ(in->name, "inBuf");
    EXPECT_EQ(in->blockName, "Input");
    EXPECT_EQ(in->kind, DescriptorKind::StorageBuffer);
    EXPECT_TRUE(in->readonly);
    EXPECT_EQ(in->imageFormat, "");

    const loom::ReflectedBinding* ubo = r.find("Params");
    ASSERT_NE(ubo, nullptr);
    EXPECT_EQ(ubo->name, "params");
    EXPECT_EQ(ubo->blockName, "Params");
    EXPECT_EQ(ubo->kind, DescriptorKind::UniformBuffer);
    EXPECT_FALSE(ubo->readonly);
    EXPECT_EQ(ubo->imageFormat, "");

    EXPECT_EQ(r.find("doesNotExist"), nullptr);
    EXPECT_EQ(r.find("Push"), nullptr) << "push constants are not descriptor bindings";
}

TEST(SpirvReflect, MainShaderPushConstantsAndLocalSize) {
    const auto words = compileCompute(kMainShader);
    ASSERT_FALSE(words.empty());
    const loom::ShaderReflection r = reflectSpirv(words);

    ASSERT_TRUE(r.pushConstants.has_value());
    const loom::ReflectedPushConstants& pc = *r.pushConstants;
    EXPECT_EQ(pc.blockName, "Push");
    EXPECT_EQ(pc.size, 32u);
    ASSERT_EQ(pc.members.size(), 4u);

    struct Expected {
        const char* name;
        uint32_t offset;
        uint32_t size;
        const char* type;
    };
    const Expected expected[] = {
        {"scale", 0, 4, "float"},
        {"mode", 4, 4, "int"},
        {"extent", 8, 8, "uvec2"},
        {"color", 16, 16, "vec4"},
    };
    for (size_t i = 0; i < 4; ++i) {
        SCOPED_TRACE(expected[i].name);
        EXPECT_EQ(pc.members[i].name, expected[i].name);
        EXPECT_EQ(pc.members[i].offset, expected[i].offset);
        EXPECT_EQ(pc.members[i].size, expected[i].size);
        EXPECT_EQ(pc.members[i].type, expected[i].type);
    }

    EXPECT_EQ(r.localSize[0], 8u);
    EXPECT_EQ(r.localSize[1], 8u);
    EXPECT_EQ(r.localSize[2], 1u);
}

TEST(SpirvReflect, ExplicitBindingsArraysAndSpirv10BufferBlock) {
    // SPIR-V 1.0 has no StorageBuffer storage class: SSBOs become Uniform + BufferBlock.
    const char* src = R"(#version 450
layout(local_size_x = 64) in;
layout(set = 1, binding = 3) uniform sampler2D tex;
layout(set = 0, binding = 5, r32ui) uniform uimage2D counters[4];
layout(set = 0, binding = 2, std430) buffer Out { uint values[]; };
layout(set = 2, binding = 0) uniform sampler samp;
layout(set = 2, binding = 1) uniform texture2D plainTex;
layout(set = 0, binding = 7, rgba16f) uniform readonly image2D roImg;
layout(set = 0, binding = 0, std430) readonly buffer Partial { uint a; float b; } partial;
layout(set = 0, binding = 1, std430) buffer Mixed { readonly uint a; float b; } mixedBuf;

void main() {
    uint i = gl_GlobalInvocationID.x;
    vec4 c = texture(tex, vec2(0.5)) + texture(sampler2D(plainTex, samp), vec2(0.5)) + imageLoad(roImg, ivec2(0));
    imageAtomicAdd(counters[i % 4u], ivec2(i, 0), 1u);
    values[i] = uint(c.x) + partial.a + mixedBuf.a;
    mixedBuf.b = partial.b;
}
)";
    const auto words = compileCompute(src, glslang::EShTargetSpv_1_0);
    ASSERT_FALSE(words.empty());
    const loom::ShaderReflection r = reflectSpirv(words);

    ASSERT_EQ(r.bindings.size(), 8u);
    const std::pair<uint32_t, uint32_t> order[] = {{0, 0}, {0, 1}, {0, 2}, {0, 5},
                                                   {0, 7}, {1, 3}, {2, 0}, {2, 1}};
    for (size_t i = 0; i < 8; ++i) {
        EXPECT_EQ(r.bindings[i].set, order[i].first) << i;
        EXPECT_EQ(r.bindings[i].binding, order[i].second) << i;
    }

    const auto* partial = r.find("partial");
    ASSERT_NE(partial, nullptr);
    EXPECT_EQ(partial->kind, DescriptorKind::StorageBuffer);
    EXPECT_TRUE(partial->readonly);

    const auto* mixed = r.find("Mixed");
    ASSERT_NE(mixed, nullptr);
    EXPECT_EQ(mixed->name, "mixedBuf");
    EXPECT_FALSE(mixed->readonly) << "only some members are NonWritable";

    // Anonymous block: the name falls back to the block name.
    const auto* out = r.find("Out");
    ASSERT_NE(out, nullptr);
    EXPECT_EQ(out->name, "Out");
    EXPECT_EQ(out->blockName, "Out");
    EXPECT_EQ(out->kind, DescriptorKind::StorageBuffer);
    EXPECT_FALSE(out->readonly);

    const auto* counters = r.find("counters");
    ASSERT_NE(counters, nullptr);
    EXPECT_EQ(counters->kind, DescriptorKind::StorageImage);
    EXPECT_EQ(counters->arraySize, 4u);
    EXPECT_EQ(counters->imageFormat, "r32ui");
    EXPECT_FALSE(counters->readonly);

    const auto* ro = r.find("roImg");
    ASSERT_NE(ro, nullptr);
    EXPECT_EQ(ro->kind, DescriptorKind::StorageImage);
    EXPECT_EQ(ro->imageFormat, "rgba16f");
    EXPECT_TRUE(ro->readonly);

    const auto* tex = r.find("tex");
    ASSERT_NE(tex, nullptr);
    EXPECT_EQ(tex->kind, DescriptorKind::SampledImage);
    EXPECT_EQ(tex->imageFormat, "");

    const auto* samp = r.find("samp");
    ASSERT_NE(samp, nullptr);
    EXPECT_EQ(samp->kind, DescriptorKind::Sampler);

    // A separate texture is not a combined image sampler.
    const auto* plain = r.find("plainTex");
    ASSERT_NE(plain, nullptr);
    EXPECT_EQ(plain->kind, DescriptorKind::Unknown);

    EXPECT_FALSE(r.pushConstants.has_value());
    EXPECT_EQ(r.localSize[0], 64u);
    EXPECT_EQ(r.localSize[1], 1u);
    EXPECT_EQ(r.localSize[2], 1u);
}

TEST(SpirvReflect, RuntimeDescriptorArrayAndMatrixPushConstant) {
    const char* src = R"(#version 450
#extension GL_EXT_nonuniform_qualifier : require
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(set = 0, binding = 0) uniform sampler2D textures[];
layout(set = 0, binding = 1, r32f) uniform image2D dst;
layout(push_constant) uniform Block { mat4 m; vec3 v; } pc;
void main() {
    vec4 c = pc.m * texture(textures[nonuniformEXT(gl_LocalInvocationIndex)], pc.v.xy);
    imageStore(dst, ivec2(0), c);
}
)";
    const auto words = compileCompute(src);
    ASSERT_FALSE(words.empty());
    const loom::ShaderReflection r = reflectSpirv(words);

    const auto* textures = r.find("textures");
    ASSERT_NE(textures, nullptr);
    EXPECT_EQ(textures->kind, DescriptorKind::SampledImage);
    EXPECT_EQ(textures->arraySize, 0u) << "runtime arrays report size 0";
    EXPECT_EQ(r.find("dst")->imageFormat, "r32f");

    ASSERT_TRUE(r.pushConstants.has_value());
    ASSERT_EQ(r.pushConstants->members.size(), 2u);
    EXPECT_EQ(r.pushConstants->members[0].type, "mat4");
    EXPECT_EQ(r.pushConstants->members[0].size, 64u);
    EXPECT_EQ(r.pushConstants->members[1].type, "vec3");
    EXPECT_EQ(r.pushConstants->members[1].offset, 64u);
    EXPECT_EQ(r.pushConstants->members[1].size, 12u);
    EXPECT_EQ(r.pushConstants->size, 76u);
    EXPECT_EQ(r.localSize[0], 4u);
    EXPECT_EQ(r.localSize[1], 4u);
    EXPECT_EQ(r.localSize[2], 4u);
}

TEST(SpirvReflect, SpecializationConstantWorkgroupSize) {
    // glslang expresses local_size_*_id through a WorkgroupSize built-in constant.
    const char* src = R"(#version 450
layout(local_size_x = 16, local_size_x_id = 0, local_size_y = 2) in;
layout(set = 0, binding = 0, std430) buffer Data { uint v[]; } data;
void main() { data.v[gl_GlobalInvocationID.x] = gl_WorkGroupSize.x; }
)";
    const auto words = compileCompute(src);
    ASSERT_FALSE(words.empty());
    const loom::ShaderReflection r = reflectSpirv(words);
    EXPECT_EQ(r.localSize[0], 16u);
    EXPECT_EQ(r.localSize[1], 2u);
    EXPECT_EQ(r.localSize[2], 1u);
}

// Hand-assembled module using OpExecutionModeId LocalSizeId (glslang does not emit it).
std::vector<uint32_t> localSizeIdModule() {
    std::vector<uint32_t> w = header();
    w.push_back(opWord(15, 3 + 2));  // OpEntryPoint GLCompute %1 "main"
    w.push_back(5);
    w.push_back(1);
    appendString(w, "main");
    w.insert(w.end(),
             {opWord(331, 6), 1, 38, 3, 4, 5});    // OpExecutionModeId %1 LocalSizeId %3 %4 %5
    w.insert(w.end(), {opWord(21, 4), 2, 32, 0});  // %2 = OpTypeInt 32 0
    w.insert(w.end(), {opWord(43, 4), 2, 3, 4});   // %3 = OpConstant %2 4
    w.insert(w.end(), {opWord(43, 4), 2, 4, 5});   // %4 = OpConstant %2 5
    w.insert(w.end(), {opWord(43, 4), 2, 5, 6});   // %5 = OpConstant %2 6
    return w;
}

TEST(SpirvReflect, LocalSizeId) {
    const loom::ShaderReflection r = reflectSpirv(localSizeIdModule());
    EXPECT_EQ(r.localSize[0], 4u);
    EXPECT_EQ(r.localSize[1], 5u);
    EXPECT_EQ(r.localSize[2], 6u);
    EXPECT_TRUE(r.bindings.empty());
    EXPECT_FALSE(r.pushConstants.has_value());
}

TEST(SpirvReflect, WorkgroupSizeBuiltInOverridesLocalSize) {
    std::vector<uint32_t> w = localSizeIdModule();
    w.insert(w.end(), {opWord(16, 6), 1, 17, 1, 1, 1});  // OpExecutionMode %1 LocalSize 1 1 1
    w.insert(w.end(), {opWord(71, 4), 9, 11, 25});       // OpDecorate %9 BuiltIn WorkgroupSize
    w.insert(w.end(), {opWord(23, 4), 8, 2, 3});         // %8 = OpTypeVector %2 3
    w.insert(w.end(), {opWord(51, 6), 8, 9, 5, 4, 3});   // %9 = OpSpecConstantComposite %8 %5 %4 %3
    const loom::ShaderReflection r = reflectSpirv(w);
    EXPECT_EQ(r.localSize[0], 6u);
    EXPECT_EQ(r.localSize[1], 5u);
    EXPECT_EQ(r.localSize[2], 4u);
}

TEST(SpirvReflect, ByteSwappedModule) {
    std::vector<uint32_t> words = localSizeIdModule();
    for (uint32_t& w : words) {
        w = ((w & 0xffu) << 24) | ((w & 0xff00u) << 8) | ((w >> 8) & 0xff00u) | (w >> 24);
    }
    const loom::ShaderReflection r = reflectSpirv(words);
    EXPECT_EQ(r.localSize[0], 4u);
    EXPECT_EQ(r.localSize[1], 5u);
    EXPECT_EQ(r.localSize[2], 6u);
}

TEST(SpirvReflect, RejectsTooShortAndBadMagic) {
    expectThrowContaining({}, "too short");
    expectThrowContaining({0x07230203u, 0x00010000u}, "too short");
    expectThrowContaining({0xdeadbeefu, 0x00010000u, 0u, 10u, 0u}, "magic");

    std::vector<uint32_t> garbage(64);
    for (size_t i = 0; i < garbage.size(); ++i) {
        garbage[i] = static_cast<uint32_t>(i * 2654435761u);
    }
    expectThrowContaining(garbage, "magic");
}

TEST(SpirvReflect, RejectsTruncatedModule) {
    const auto words = compileCompute(kMainShader);
    ASSERT_GT(words.size(), 5u);

    // Cut inside a multi-word instruction so the stream ends mid-instruction.
    size_t pos = 5;
    size_t cut = 0;
    while (pos < words.size()) {
        const size_t count = words[pos] >> 16;
        ASSERT_GT(count, 0u);
        if (count > 2 && pos > words.size() / 2) {
            cut = pos + 2;
            break;
        }
        pos += count;
    }
    ASSERT_NE(cut, 0u);
    expectThrowContaining(
        std::vector<uint32_t>(words.begin(), words.begin() + static_cast<std::ptrdiff_t>(cut)),
        "truncated");

    std::vector<uint32_t> shortInst = header();
    shortInst.insert(shortInst.end(), {opWord(21, 4), 2});  // OpTypeInt claims 4 words, has 2
    expectThrowContaining(shortInst, "truncated");
}

TEST(SpirvReflect, RejectsMalformedInstructions) {
    std::vector<uint32_t> zeroCount = header();
    zeroCount.push_back(0u);
    expectThrowContaining(zeroCount, "word count of zero");

    std::vector<uint32_t> unterminated = header();
    unterminated.insert(unterminated.end(),
                        {opWord(5, 3), 1, 0x64636261u});  // OpName %1 "abcd" without nul
    expectThrowContaining(unterminated, "unterminated string");

    std::vector<uint32_t> missingOperand = header();
    missingOperand.insert(missingOperand.end(),
                          {opWord(71, 3), 1, 33});  // Binding without its literal
    expectThrowContaining(missingOperand, "too few operands");

    // A struct containing itself would recurse forever without the depth guard.
    std::vector<uint32_t> cyclic = header();
    cyclic.insert(cyclic.end(), {opWord(30, 3), 1, 1});     // %1 = OpTypeStruct %1
    cyclic.insert(cyclic.end(), {opWord(32, 4), 2, 9, 1});  // %2 = OpTypePointer PushConstant %1
    cyclic.insert(cyclic.end(), {opWord(59, 4), 2, 3, 9});  // %3 = OpVariable %2 PushConstant
    expectThrowContaining(cyclic, "too deep");

    std::vector<uint32_t> notPointer = header();
    notPointer.insert(notPointer.end(), {opWord(59, 4), 7, 3, 2});  // variable with undefined type
    expectThrowContaining(notPointer, "pointer type");
}

TEST(SpirvReflect, MutatedModulesNeverCrash) {
    // Corrupted input must either reflect or throw std::runtime_error, never crash or hang.
    const auto words = compileCompute(kMainShader);
    ASSERT_FALSE(words.empty());
    std::mt19937 rng(1234);
    for (int iteration = 0; iteration < 2000; ++iteration) {
        std::vector<uint32_t> mutated = words;
        const int edits = 1 + iteration % 4;
        for (int e = 0; e < edits; ++e) {
            const size_t index = 5 + rng() % (mutated.size() - 5);
            mutated[index] = (iteration % 2) ? static_cast<uint32_t>(rng())
                                             : (mutated[index] ^ (1u << (rng() % 32)));
        }
        if (iteration % 7 == 0) {
            mutated.resize(5 + rng() % (mutated.size() - 5));
        }
        try {
            (void)reflectSpirv(mutated);
        } catch (const std::runtime_error&) {
        }
    }
}

}  // namespace

// A shared library declares buffers a kernel may never read; glslang gives such dead
// resources binding 0, so they must not reach the descriptor layout (duplicate bindings).
TEST(SpirvReflect, DeadResourcesAreNotReflected) {
    const char* src = R"(#version 460
layout(local_size_x = 1) in;
layout(std430) readonly buffer Unused { float unused_data[]; };
layout(std430) readonly buffer Used { float used_data[]; };
layout(r32f) uniform image2D dst;
layout(r32f) uniform image2D deadImage;
void main() { imageStore(dst, ivec2(0), vec4(used_data[0])); }
)";
    const auto words = compileCompute(src);
    ASSERT_FALSE(words.empty());
    const loom::ShaderReflection r = reflectSpirv(words);
    EXPECT_NE(r.find("Used"), nullptr);
    EXPECT_NE(r.find("dst"), nullptr);
    EXPECT_EQ(r.find("Unused"), nullptr);
    EXPECT_EQ(r.find("deadImage"), nullptr);
    std::set<uint32_t> seen;
    for (const auto& b : r.bindings) EXPECT_TRUE(seen.insert(b.binding).second) << b.name;
}
