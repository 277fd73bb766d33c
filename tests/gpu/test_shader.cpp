// Shader system: #include resolution, defines, the on-disk SPIR-V cache and its keys, hot
// reload and error messages. Every shader is written to a temporary directory by the test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "core/shader/ShaderCompiler.h"
#include "tests/support/GpuSupport.h"

namespace {

namespace fs = std::filesystem;
using loom::ShaderCompileError;
using loom::ShaderCompiler;
using loom::test::TempDir;
using loom::test::writeFile;

std::string canonical(const std::string& p) {
    return fs::weakly_canonical(p).string();
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
    return std::find(v.begin(), v.end(), s) != v.end();
}

// A kernel that writes VALUE() (from an include) to out[0]; `includeLine` is its #include.
std::string storeKernel(const std::string& includeLine, const std::string& expr = "VALUE()") {
    return "#version 460\n" + includeLine +
           "\n"
           "layout(local_size_x = 1) in;\n"
           "layout(std430) buffer Out { float result[]; };\n"
           "void main() { result[0] = " +
           expr + "; }\n";
}

class ShaderTest : public ::testing::Test {
protected:
    TempDir dir{"loom-shader"};
    std::string cacheDir() const { return dir / "cache"; }
    std::string file(const std::string& rel, const std::string& text) {
        writeFile(dir / rel, text);
        return dir / rel;
    }

    // Runs a single-thread kernel that stores one float in "result" and returns it.
    float run(const loom::CompiledShader& shader) {
        auto gpu = loom::test::gpuContext();
        auto pipeline = gpu->createPipeline(shader.spirv, shader.reflection, shader.path);
        auto buffer = gpu->createBuffer(16, "result");
        loom::gpu::Bindings b;
        b.set("Out", buffer);
        auto cmd = gpu->beginCommands();
        cmd->fillBuffer(*buffer, 0);
        cmd->barrier();
        cmd->dispatch(*pipeline, b, nullptr, 1);
        gpu->submit(*cmd);
        float v = -1.0f;
        gpu->downloadBuffer(*buffer, &v, sizeof(v));
        return v;
    }
};

TEST_F(ShaderTest, IncludeFromSearchPaths) {
    file("first/common.glsl", "float VALUE() { return 1.5; }\n");
    file("second/common.glsl", "float VALUE() { return 2.5; }\n");
    file("second/only_second.glsl", "float OTHER() { return 4.0; }\n");
    std::string main = file("src/main.comp", storeKernel("#include \"common.glsl\"\n"
                                                         "#include <only_second.glsl>",
                                                         "VALUE() + OTHER()"));
    ShaderCompiler c({dir / "first", dir / "second"}, "");
    auto s = c.compile(main);
    EXPECT_EQ(s->path, canonical(main));
    // The first search path that has the file wins.
    EXPECT_TRUE(contains(s->sources, canonical(dir / "first/common.glsl")));
    EXPECT_FALSE(contains(s->sources, canonical(dir / "second/common.glsl")));
    EXPECT_TRUE(contains(s->sources, canonical(dir / "second/only_second.glsl")));
    EXPECT_EQ(run(*s), 5.5f);
    // The main file itself is found through the search paths too.
    file("first/kernels/k.comp", storeKernel("#include \"common.glsl\""));
    ShaderCompiler c2({dir / "first"}, "");
    EXPECT_EQ(c2.compile("kernels/k.comp")->path, canonical(dir / "first/kernels/k.comp"));
}

TEST_F(ShaderTest, SystemIncludeComesFromSearchPathsOnly) {
    // <value.glsl> is the search path's file even when one with the same name sits next to the
    // including file; the cache key must track that same file.
    std::string used = file("lib/value.glsl", "float VALUE() { return 2.0; }\n");
    file("src/value.glsl", "float VALUE() { return -1.0; }\n");
    std::string main = file("src/main.comp", storeKernel("#include <value.glsl>"));
    ShaderCompiler c({dir / "lib"}, cacheDir());
    auto s = c.compile(main);
    EXPECT_EQ(run(*s), 2.0f);
    EXPECT_EQ(s->sources, (std::vector<std::string>{canonical(main), canonical(used)}));
    writeFile(used, "float VALUE() { return 3.0; }\n");
    EXPECT_EQ(c.reloadChanged(), 1u) << "an edit of the included file went unnoticed";
    EXPECT_EQ(run(*c.compile(main)), 3.0f);
}

TEST_F(ShaderTest, IncludeRelativeToIncludingFile) {
    // main.comp includes sub/a.glsl, which includes "b.glsl": that must be sub/b.glsl (next to
    // a.glsl), not the decoy next to main.comp or on the search path.
    file("src/sub/a.glsl", "#include \"b.glsl\"\nfloat VALUE() { return B_VALUE() * 2.0; }\n");
    file("src/sub/b.glsl", "float B_VALUE() { return 3.25; }\n");
    file("src/b.glsl", "this is not GLSL\n");
    file("lib/b.glsl", "this is not GLSL either\n");
    std::string main = file("src/main.comp", storeKernel("#include \"sub/a.glsl\""));
    ShaderCompiler c({dir / "lib"}, "");
    auto s = c.compile(main);
    EXPECT_EQ(s->sources,
              (std::vector<std::string>{canonical(main), canonical(dir / "src/sub/a.glsl"),
                                        canonical(dir / "src/sub/b.glsl")}));
    EXPECT_EQ(run(*s), 6.5f);
}

TEST_F(ShaderTest, DefinesProduceDifferentSpirv) {
    std::string main = file("main.comp", storeKernel("#define VALUE() (SCALE * 2.0)"));
    ShaderCompiler c({}, "");
    auto a = c.compile(main, {{"SCALE", "1.25"}});
    auto b = c.compile(main, {{"SCALE", "3.0"}});
    EXPECT_NE(a->spirv, b->spirv);
    EXPECT_NE(a->key, b->key);
    EXPECT_EQ(run(*a), 2.5f);
    EXPECT_EQ(run(*b), 6.0f);
    // The same defines again come from memory.
    EXPECT_EQ(c.compile(main, {{"SCALE", "1.25"}}).get(), a.get());
    EXPECT_EQ(c.stats().compiles, 2u);
    EXPECT_EQ(c.stats().memoryHits, 1u);
}

// Global defines ($LOOM_SHADER_DEFINES) reach every compile, under the shader's own, and are
// part of the cache key (a test that injects a bias never reuses unbiased SPIR-V).
TEST_F(ShaderTest, GlobalDefinesFromEnvironment) {
    std::string main = file("main.comp", storeKernel("#define VALUE() (SCALE * OFFSET)"));
    ::setenv("LOOM_SHADER_DEFINES", "SCALE=3.0; OFFSET=2.0", 1);
    ShaderCompiler c({}, cacheDir());
    ::unsetenv("LOOM_SHADER_DEFINES");
    EXPECT_EQ(c.globalDefines().size(), 2u);
    EXPECT_EQ(run(*c.compile(main)), 6.0f);
    EXPECT_EQ(run(*c.compile(main, {{"SCALE", "0.5"}})), 1.0f);  // the shader's own wins
    ShaderCompiler plain({}, cacheDir());
    auto p = plain.compile(main, {{"SCALE", "1.0"}, {"OFFSET", "1.0"}});
    EXPECT_FALSE(p->fromDiskCache);
    EXPECT_EQ(run(*p), 1.0f);
    EXPECT_EQ(loom::parseShaderDefines("A;B=2")["A"], "1");
    EXPECT_THROW(loom::parseShaderDefines("1X=2"), loom::UserError);
}

// Mesa's llvmpipe (lavapipe) stops a loop after 65535 iterations per invocation, summed over
// every entry into that loop, silently (LP_MAX_TGSI_LOOP_ITERATIONS): a kernel that loops
// longer than that gives wrong results, not an error. Passes keep their per-dispatch loops
// below it (PathTracer splits its samples into dispatches); this test records the limit.
TEST_F(ShaderTest, LoopIterationsPerInvocation) {
    std::string main = file("loops.comp", R"(#version 460
layout(local_size_x = 1) in;
layout(std430) buffer Out { float result[]; };
layout(push_constant) uniform P { uint outer; uint inner; } pc;
void main() {
    uint n = 0u;
    for (uint i = 0u; i < OUTER; ++i)
        for (uint j = 0u; j < INNER; ++j) n++;
    result[0] = float(n);
}
)");
    ShaderCompiler c({}, "");
    float small = run(*c.compile(main, {{"OUTER", "100u"}, {"INNER", "100u"}}));
    EXPECT_EQ(small, 10000.0f);
    float large = run(*c.compile(main, {{"OUTER", "400u"}, {"INNER", "400u"}}));
    std::printf("nested loops of 400 x 400 iterations ran %.0f inner iterations\n", large);
}

TEST_F(ShaderTest, DiskCacheHitOnSecondCompiler) {
    file("inc/value.glsl", "float VALUE() { return 7.0; }\n");
    std::string main = file("main.comp", storeKernel("#include \"inc/value.glsl\""));
    ShaderCompiler first({}, cacheDir());
    auto a = first.compile(main, {{"MODE", "1"}});
    EXPECT_EQ(first.stats().compiles, 1u);
    EXPECT_EQ(first.stats().diskHits, 0u);
    EXPECT_FALSE(a->fromDiskCache);
    EXPECT_TRUE(fs::exists(cacheDir() + "/spirv/" + a->key + ".spv"));

    ShaderCompiler second({}, cacheDir());
    auto b = second.compile(main, {{"MODE", "1"}});
    EXPECT_EQ(second.stats().compiles, 0u);
    EXPECT_EQ(second.stats().diskHits, 1u);
    EXPECT_TRUE(b->fromDiskCache);
    EXPECT_EQ(b->spirv, a->spirv);
    EXPECT_EQ(b->key, a->key);
    ASSERT_EQ(b->reflection.bindings.size(), 1u);
    EXPECT_EQ(b->reflection.bindings[0].name, "Out");
    EXPECT_EQ(run(*b), 7.0f);

    // Other defines are another cache entry.
    second.compile(main, {{"MODE", "2"}});
    EXPECT_EQ(second.stats().compiles, 1u);

    // A corrupt entry is recompiled, not trusted.
    writeFile(cacheDir() + "/spirv/" + a->key + ".spv", std::string(64, '\x7f'));
    ShaderCompiler third({}, cacheDir());
    auto c = third.compile(main, {{"MODE", "1"}});
    EXPECT_EQ(third.stats().compiles, 1u);
    EXPECT_EQ(third.stats().diskHits, 0u);
    EXPECT_EQ(c->spirv, a->spirv);
}

TEST_F(ShaderTest, CacheKeyChangesWhenIncludedFileChanges) {
    std::string inc = file("inc/value.glsl", "float VALUE() { return 1.0; }\n");
    file("inc/deeper.glsl", "float DEEP() { return 0.5; }\n");
    std::string main = file("main.comp", storeKernel("#include \"inc/value.glsl\""));
    ShaderCompiler c({}, cacheDir());
    std::string path = c.resolve(main);
    std::string key0 = c.cacheKey(path, {});
    EXPECT_EQ(c.cacheKey(path, {}), key0);  // stable
    EXPECT_NE(c.cacheKey(path, {{"X", "1"}}), key0);
    c.compile(main);

    writeFile(inc, "float VALUE() { return 2.0; }\n");
    std::string key1 = c.cacheKey(path, {});
    EXPECT_NE(key1, key0);
    ShaderCompiler fresh({}, cacheDir());
    auto s = fresh.compile(main);
    EXPECT_EQ(fresh.stats().diskHits, 0u) << "stale SPIR-V served after an include changed";
    EXPECT_EQ(fresh.stats().compiles, 1u);
    EXPECT_EQ(run(*s), 2.0f);

    // A change two includes deep counts too.
    writeFile(inc, "#include \"deeper.glsl\"\nfloat VALUE() { return DEEP(); }\n");
    std::string key2 = c.cacheKey(path, {});
    writeFile(dir / "inc/deeper.glsl", "float DEEP() { return 0.75; }\n");
    EXPECT_NE(c.cacheKey(path, {}), key2);

    // Restoring the original text finds the original entry again.
    writeFile(inc, "float VALUE() { return 1.0; }\n");
    EXPECT_EQ(c.cacheKey(path, {}), key0);
    ShaderCompiler again({}, cacheDir());
    auto t = again.compile(main);
    EXPECT_EQ(again.stats().diskHits, 1u);
    EXPECT_EQ(run(*t), 1.0f);
}

TEST_F(ShaderTest, ReloadChangedPicksUpEdits) {
    std::string inc = file("inc/value.glsl", "float VALUE() { return 10.0; }\n");
    std::string main = file("main.comp", storeKernel("#include \"inc/value.glsl\""));
    ShaderCompiler c({}, cacheDir());
    auto a = c.compile(main);
    EXPECT_EQ(c.reloadChanged(), 0u);
    EXPECT_EQ(c.generation(), 0u);
    EXPECT_EQ(c.compile(main).get(), a.get());

    writeFile(inc, "float VALUE() { return 20.0; }\n");
    EXPECT_EQ(c.compile(main).get(), a.get()) << "memory cache is kept until reloadChanged()";
    EXPECT_EQ(c.reloadChanged(), 1u);
    EXPECT_EQ(c.generation(), 1u);
    auto b = c.compile(main);
    EXPECT_NE(b.get(), a.get());
    EXPECT_EQ(run(*b), 20.0f);
    EXPECT_EQ(c.stats().compiles, 2u);

    // An edit of the main file is picked up as well.
    writeFile(main, storeKernel("#include \"inc/value.glsl\"", "VALUE() + 1.0"));
    EXPECT_EQ(c.reloadChanged(), 1u);
    EXPECT_EQ(run(*c.compile(main)), 21.0f);
    EXPECT_EQ(c.reloadChanged(), 0u);
    EXPECT_EQ(c.generation(), 2u);
}

TEST_F(ShaderTest, UnusedResourcesGetTheirOwnBinding) {
    // glslang leaves an unused resource at binding 0, where it collides with a used one.
    std::string main = file("main.comp",
                            "#version 460\n"
                            "layout(local_size_x = 1) in;\n"
                            "layout(std430) buffer Out { float result[]; };\n"
                            "layout(r32f) uniform writeonly image2D unusedImage;\n"
                            "layout(std430) buffer Unused { float unused[]; };\n"
                            "void main() { result[0] = 4.5; }\n");
    ShaderCompiler c({}, "");
    auto s = c.compile(main);
    // Dead resources may be left out of the reflection; those reflected must not collide.
    ASSERT_FALSE(s->reflection.bindings.empty());
    std::set<uint32_t> numbers;
    for (const auto& b : s->reflection.bindings) numbers.insert(b.binding);
    EXPECT_EQ(numbers.size(), s->reflection.bindings.size())
        << "two resources share a binding number";

    // Bound by name, the used buffer receives the value.
    auto gpu = loom::test::gpuContext();
    auto pipeline = gpu->createPipeline(s->spirv, s->reflection, s->path);
    auto out = gpu->createBuffer(16, "out"), unused = gpu->createBuffer(16, "unused");
    auto image = gpu->createImage(2, 2, loom::gpu::Format::R32F, "unusedImage");
    loom::gpu::Bindings b;
    b.set("Out", out).set("Unused", unused).set("unusedImage", image);
    auto cmd = gpu->beginCommands();
    cmd->fillBuffer(*out, 0);
    cmd->barrier();
    cmd->dispatch(*pipeline, b, nullptr, 1);
    gpu->submit(*cmd);
    float v = 0.0f;
    gpu->downloadBuffer(*out, &v, sizeof(v));
    EXPECT_EQ(v, 4.5f);
    EXPECT_EQ(gpu->validationErrors(), 0u);
}

// Returns the ShaderCompileError message of compiling `path`.
std::string compileError(ShaderCompiler& c, const std::string& path) {
    try {
        c.compile(path);
    } catch (const ShaderCompileError& e) {
        return e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected ShaderCompileError, got: " << e.what();
        return e.what();
    }
    ADD_FAILURE() << path << " compiled";
    return "";
}

TEST_F(ShaderTest, CompileErrorNamesFileLineAndSourceText) {
    std::string main = file("bad.comp",
                            "#version 460\n"
                            "layout(local_size_x = 1) in;\n"
                            "layout(std430) buffer Out { float result[]; };\n"
                            "void main() {\n"
                            "    result[0] = undefined_thing * 2.0;\n"
                            "}\n");
    ShaderCompiler c({}, "");
    std::string msg = compileError(c, main);
    std::string where = canonical(main) + ":5: error: ";
    EXPECT_NE(msg.find(where), std::string::npos) << msg;
    EXPECT_NE(msg.find("undefined_thing"), std::string::npos) << msg;
    EXPECT_NE(msg.find("\n    " + std::string("    result[0] = undefined_thing * 2.0;")),
              std::string::npos)
        << msg;
}

TEST_F(ShaderTest, CompileErrorInIncludedFile) {
    file("inc/broken.glsl",
         "// helper\n"
         "float VALUE() {\n"
         "    return missing_symbol;\n"
         "}\n");
    std::string main = file("main.comp", storeKernel("#include \"inc/broken.glsl\""));
    ShaderCompiler c({}, "");
    std::string msg = compileError(c, main);
    EXPECT_NE(msg.find(canonical(dir / "inc/broken.glsl") + ":3: error: "), std::string::npos)
        << msg;
    EXPECT_NE(msg.find("\n        return missing_symbol;"), std::string::npos) << msg;
}

TEST_F(ShaderTest, MissingIncludeError) {
    std::string main = file("main.comp", storeKernel("#include \"nowhere/missing.glsl\""));
    ShaderCompiler c({dir / "lib"}, "");
    std::string msg = compileError(c, main);
    EXPECT_NE(msg.find(canonical(main) + ":2: error: "), std::string::npos) << msg;
    EXPECT_NE(msg.find("nowhere/missing.glsl"), std::string::npos) << msg;
    EXPECT_NE(msg.find("#include \"nowhere/missing.glsl\""), std::string::npos) << msg;
}

TEST_F(ShaderTest, MissingShaderAndVersion) {
    ShaderCompiler c({dir / "lib"}, "");
    try {
        c.compile("absent.comp");
        FAIL() << "missing shader compiled";
    } catch (const loom::UserError& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("shader file 'absent.comp' not found"), std::string::npos) << msg;
        EXPECT_NE(msg.find((dir / "lib") + "/absent.comp"), std::string::npos) << msg;
    }
    std::string noVersion = file("nov.comp", "layout(local_size_x = 1) in;\nvoid main() {}\n");
    EXPECT_EQ(compileError(c, noVersion),
              canonical(noVersion) + ":1: error: shader has no #version line (use #version 460)");
}

}  // namespace

// CommandList::dispatchIndirect: a kernel writes the next dispatch's group counts (at an
// offset), the indirect dispatch runs exactly that many groups, zero groups run nothing, and
// arguments outside the buffer are an error naming it.
TEST_F(ShaderTest, IndirectDispatchTakesGroupCountsFromTheDevice) {
    auto gpu = loom::test::gpuContext();
    ShaderCompiler c({dir.path()}, "");
    auto writer = c.compile(file("writer.comp", R"(#version 460
layout(local_size_x = 1) in;
layout(std430) buffer Args { uint args[]; };
layout(push_constant) uniform P { uint groups; } pc;
void main() { args[4] = pc.groups; args[5] = 2u; args[6] = 1u; }
)"));
    auto counter = c.compile(file("counter.comp", R"(#version 460
layout(local_size_x = 4, local_size_y = 2) in;
layout(std430) buffer Count { uint count; };
void main() { atomicAdd(count, 1u); }
)"));
    auto pw = gpu->createPipeline(writer->spirv, writer->reflection, writer->path);
    auto pcnt = gpu->createPipeline(counter->spirv, counter->reflection, counter->path);
    auto args = gpu->createBuffer(7 * 4, "args");
    auto count = gpu->createBuffer(4, "count");
    for (uint32_t groups : {3u, 0u}) {
        loom::gpu::Bindings b;
        b.set("Args", args).set("Count", count);
        loom::gpu::PushConstants push(*pw);
        push.set("groups", groups);
        auto cmd = gpu->beginCommands();
        cmd->fillBuffer(*count, 0);
        cmd->barrier();
        cmd->dispatch(*pw, b, &push, 1);
        cmd->barrier();
        cmd->dispatchIndirect(*pcnt, b, nullptr, *args, 16);
        gpu->submit(*cmd);
        uint32_t n = ~0u;
        gpu->downloadBuffer(*count, &n, 4);
        EXPECT_EQ(n, groups * 2 * 8) << groups << " x 2 groups of 8 invocations";
    }
    loom::gpu::Bindings b;
    b.set("Count", count);
    auto cmd = gpu->beginCommands();
    try {
        cmd->dispatchIndirect(*pcnt, b, nullptr, *args, 20);
        FAIL() << "arguments past the end of the buffer must be an error";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("args"), std::string::npos) << e.what();
    }
}
