// Bad input through the loom binary, one case per class of the hostile sweep (issue 21), in
// every format: each must exit with code 2 (or warn and go on where that is the rule) and name
// the offending file and line or key. Never a crash, a hang or a damaged output file.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/support/TestSupport.h"

namespace {

using loom::test::readFile;
using loom::test::TempDir;
using loom::test::writeFile;

const std::string kSource = LOOM_SOURCE_DIR;

struct Result {
    int exitCode = -1;  // -1: killed by a signal (a crash)
    std::string out, err;
};

// Runs `loom ARGS` in `dir` under a 120 s timeout (a hang fails the test); `prefix` runs first
// in the same shell (ulimit). stdout and stderr are kept apart.
Result runLoom(const TempDir& dir, const std::string& args, const std::string& prefix = "") {
    std::string cmd = "cd '" + dir.str() + "' && " + prefix + " LOOM_PROGRESS=0 timeout 120 '" +
                      LOOM_BINARY + "' " + args + " >'" + (dir / "stdout") + "' 2>'" +
                      (dir / "stderr") + "'";
    int status = std::system(("bash -c \"" + cmd + "\"").c_str());
    Result r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = readFile(dir / "stdout");
    r.err = readFile(dir / "stderr");
    return r;
}

std::string repeat(const std::string& s, int n) {
    std::string r;
    for (int i = 0; i < n; ++i) r += s;
    return r;
}

// Exit code 2 and every fragment in the message.
void expectNamedError(const Result& r, const std::vector<std::string>& fragments) {
    EXPECT_EQ(r.exitCode, 2) << r.err;
    for (const auto& f : fragments) EXPECT_NE(r.err.find(f), std::string::npos) << r.err;
}

const char* kGraph = "'" LOOM_SOURCE_DIR "/graphs/pt.json'";
const std::string kSmall = " --width 8 --height 8 --out out.exr";

// A one-triangle glTF whose material and camera are set by the caller.
std::string gltf(const std::string& material, const std::string& camera) {
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}],
  "cameras": [)" +
           camera + R"(],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
  "materials": [)" +
           material + R"(],
  "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]}]})";
}

// A Loom JSON scene: one emissive quad over one diffuse floor with `reflectance`.
std::string jsonScene(const std::string& reflectance, const std::string& extraShape = "") {
    return R"({"camera": {"origin": [0, 1, 4], "target": [0, 0, 0], "fov": 40,
  "path": [{"time": 0, "origin": [0, 1, 4], "target": [0, 0, 0]}]},
  "materials": {"floor": {"type": "diffuse", "reflectance": )" +
           reflectance + R"(}},
  "shapes": [{"type": "rectangle", "material": "floor"},
             {"type": "rectangle", "emission": 5, "transform": [{"translate": [0, 2, 0]}]})" +
           extraShape + "]}";
}

TEST(BadInput, DeepNestingIsANamedErrorInEveryFormat) {
    TempDir d("loom-bad");
    std::string deep = repeat("[", 50000) + repeat("]", 50000);
    writeFile(d / "deep.json", deep);
    expectNamedError(runLoom(d, "validate deep.json"), {"deep.json:1:257", "nested deeper"});
    expectNamedError(runLoom(d, std::string("render ") + kGraph + " --scene deep.json" + kSmall),
                     {"deep.json:1:257", "nested deeper"});
    writeFile(d / "deep.xml", "<scene version=\"3.0.0\">\n<shape type=\"sphere\">" +
                                  repeat("<bsdf type=\"twosided\">", 20000) +
                                  repeat("</bsdf>", 20000) + "</shape></scene>\n");
    expectNamedError(runLoom(d, std::string("render ") + kGraph + " --scene deep.xml" + kSmall),
                     {"deep.xml:2", "nested deeper"});
    // Lua tables: 18 levels encode (the old crash), 300 are a named error.
    writeFile(d / "ok.lua",
              "local t = {} local c = t for i = 1, 18 do c.x = {} c = c.x end "
              "print(#loom.json_encode(t))\n");
    Result ok = runLoom(d, "run ok.lua");
    EXPECT_EQ(ok.exitCode, 0) << ok.err;
    EXPECT_NE(ok.out.find("110"), std::string::npos) << ok.out;  // 18 x '{"x":' + '{}' + 18 '}'
    writeFile(d / "deep.lua",
              "local t = {} local c = t for i = 1, 300 do c.x = {} c = c.x end\n"
              "loom.json_encode(t)\n");
    expectNamedError(runLoom(d, "run deep.lua"), {"deep.lua:2", "nested deeper"});
}

TEST(BadInput, CyclesAreNamedErrors) {
    TempDir d("loom-bad");
    writeFile(d / "self.xml",
              "<scene version=\"3.0.0\">\n  <include filename=\"self.xml\"/>\n</scene>\n");
    expectNamedError(runLoom(d, std::string("render ") + kGraph + " --scene self.xml" + kSmall),
                     {"self.xml:2", "include cycle"});
    writeFile(d / "refs.xml", R"(<scene version="3.0.0">
  <bsdf type="twosided" id="a"><ref id="b"/></bsdf>
  <bsdf type="twosided" id="b"><ref id="a"/></bsdf>
  <shape type="sphere"><ref id="a"/></shape>
</scene>
)");
    expectNamedError(runLoom(d, std::string("render ") + kGraph + " --scene refs.xml" + kSmall),
                     {"refs.xml:2", "reference cycle", "id=\"b\""});
    writeFile(d / "cycle.lua", "local t = {} t.self = t\nloom.write_json('c.json', t)\n");
    expectNamedError(runLoom(d, "run cycle.lua"), {"cycle.lua:2", "contains itself"});
    EXPECT_FALSE(std::filesystem::exists(d / "c.json"));
}

TEST(BadInput, NumbersOutOfRangeNameTheirSource) {
    TempDir d("loom-bad");
    writeFile(d / "g.json",
              "{\"name\": \"g\",\n \"passes\": [{\"name\": \"tm\", \"type\": "
              "\"ToneMap\", \"params\": {\"exposure\": 1e400}}]}\n");
    expectNamedError(runLoom(d, "validate g.json"), {"g.json:2:", "out of range", "1e400"});
    expectNamedError(
        runLoom(d, std::string("render ") + kGraph + " --set pt.maxBounces=1e400" + kSmall),
        {"--set pt.maxBounces", "out of range"});
    expectNamedError(
        runLoom(d, std::string("render ") + kGraph + " --set pt.maxBounces=1e30" + kSmall),
        {"maxBounces"});
    writeFile(
        d / "grass.json",
        jsonScene("0.5", R"(, {"type": "grass", "blades": 1000000000, "material": "floor"})"));
    expectNamedError(runLoom(d, std::string("render ") + kGraph + " --scene grass.json" + kSmall),
                     {"grass.json:", "blades"});
}

// The same rules in every format: negative or non-finite reflectance is an error naming where
// the material is, above 1 a warning; a fov of 0 or 180 is an error; a scene that cannot emit
// is a warning.
TEST(BadInput, PhysicalRangesAreCheckedInEveryFormat) {
    TempDir d("loom-bad");
    auto render = [&](const std::string& scene) {
        return runLoom(d, std::string("render ") + kGraph + " --scene " + scene + kSmall);
    };
    writeFile(d / "neg.json", jsonScene("-1"));
    expectNamedError(render("neg.json"), {"neg.json:", "material 'floor'", "negative"});
    writeFile(d / "inf.json", jsonScene("1e39"));
    expectNamedError(render("inf.json"), {"inf.json:", "not finite"});
    writeFile(d / "bright.json", jsonScene("1.5"));
    Result bright = render("bright.json");
    EXPECT_EQ(bright.exitCode, 0) << bright.err;
    EXPECT_NE(bright.err.find("exceeds 1"), std::string::npos) << bright.err;

    writeFile(d / "neg.xml", R"(<scene version="3.0.0">
  <emitter type="constant"/>
  <shape type="sphere">
    <bsdf type="diffuse"><rgb name="reflectance" value="-1, 0.5, 0.5"/></bsdf>
  </shape>
</scene>
)");
    expectNamedError(render("neg.xml"), {"neg.xml:4", "negative"});
    writeFile(d / "dark.xml", "<scene version=\"3.0.0\">\n  <shape type=\"sphere\"/>\n</scene>\n");
    Result dark = render("dark.xml");
    EXPECT_EQ(dark.exitCode, 0) << dark.err;
    EXPECT_NE(dark.err.find("no emitter that can emit light"), std::string::npos) << dark.err;

    writeFile(d / "m.mtl", "# materials\nnewmtl bad\nKd -1 nan 0.5\n");
    writeFile(d / "m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl bad\nf 1 2 3\n");
    expectNamedError(render("m.obj"), {"m.mtl:2", "material 'bad'"});

    writeFile(d / "neg.gltf",
              gltf(R"({"pbrMetallicRoughness": {"baseColorFactor": [-1, -5, 2, 1]}})",
                   R"({"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}})"));
    expectNamedError(render("neg.gltf"), {"neg.gltf: materials[0]", "negative"});
    writeFile(d / "fov.gltf",
              gltf("{}", R"({"type": "perspective", "perspective": {"yfov": 0, "znear": 0.1}})"));
    expectNamedError(render("fov.gltf"), {"fov.gltf", "fov"});
    writeFile(d / "fov.json", jsonScene("0.5"));
    // JSON and XML cameras reject fov 0 in their loaders already; the same rule, same code 2.
    std::string s = readFile(d / "fov.json");
    s.replace(s.find("\"fov\": 40"), 9, "\"fov\": 0");
    writeFile(d / "fov.json", s);
    expectNamedError(render("fov.json"), {"fov.json:", "fov"});
}

// Inputs the fuzzers found (fuzz/README.md): each once crashed a loader or left it with an
// exception that was not a named error.
TEST(BadInput, FuzzerFindingsAreNamedErrors) {
    TempDir d("loom-bad");
    // fuzz_mitsuba_xml: a non-hex '#rrggbb' colour threw std::invalid_argument from stoi
    // ("#33)699"), or was read in part ("#3)6699" as 3).
    for (const char* colour : {"#33)699", "#3)6699", "#zzzzzz"}) {
        writeFile(d / "hex.xml", std::string(R"(<scene version="0.5.0">
  <shape type="sphere">
    <bsdf type="plastic"><srgb name="diffuseReflectance" value=")") +
                                     colour +
                                     R"("/></bsdf>
  </shape>
</scene>
)");
        expectNamedError(runLoom(d, std::string("render ") + kGraph + " --scene hex.xml" + kSmall),
                         {"hex.xml:3", "#rrggbb", colour});
    }
    // fuzz_mitsuba_xml (UBSan): an <integer> of 1e39 or 3e9 was converted to int (undefined
    // behaviour; a film width of 1e39 came out as some int).
    for (const char* big : {"1e39", "3e9", "-3e9"}) {
        writeFile(d / "int.xml",
                  std::string("<scene version=\"3.0.0\">\n  <sensor type=\"perspective\">\n"
                              "    <film type=\"hdrfilm\"><integer name=\"width\" "
                              "value=\"") +
                      big + "\"/></film>\n  </sensor>\n  <shape type=\"sphere\"/>\n</scene>\n");
        expectNamedError(runLoom(d, std::string("render ") + kGraph + " --scene int.xml" + kSmall),
                         {"int.xml:3", "out of range"});
    }
    writeFile(d / "film.xml",
              "<scene version=\"3.0.0\">\n  <sensor type=\"perspective\">\n"
              "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"-5\"/>"
              "</film>\n  </sensor>\n  <shape type=\"sphere\"/>\n</scene>\n");
    expectNamedError(runLoom(d, std::string("render ") + kGraph + " --scene film.xml" + kSmall),
                     {"film.xml:3", "film size -5x576"});
}

TEST(BadInput, ComputePassDispatchesWithinTheDeviceLimits) {
    TempDir d("loom-bad");
    writeFile(d / "k.comp",
              "#version 460\nlayout(local_size_x = 8, local_size_y = 8) in;\n"
              "layout(rgba32f) uniform writeonly image2D outImage;\n"
              "void main() { imageStore(outImage, ivec2(gl_GlobalInvocationID.xy), vec4(1)); }\n");
    auto graph = [&](const std::string& name, const std::string& shader,
                     const std::string& dispatch) {
        writeFile(d / name, R"({"name": "k", "passes": [{"name": "k", "type": "ComputePass",
  "params": {"shader": ")" + shader +
                                "\"" + dispatch + R"(,
    "outputs": {"out": {"glsl": "outImage", "format": "rgba32f"}}}}],
  "edges": [], "outputs": ["k.out"]})");
    };
    graph("wrap.json", "k.comp", ", \"dispatch\": [4294967296, 1, 1]");
    expectNamedError(runLoom(d, "validate wrap.json"), {"wrap.json:", "'dispatch'"});
    graph("huge.json", "k.comp", ", \"dispatch\": [2147483647, 1, 1]");
    expectNamedError(runLoom(d, "render huge.json" + kSmall),
                     {"pass 'k'", "2147483647x1x1 threads", "maxComputeWorkGroupCount"});
    EXPECT_FALSE(std::filesystem::exists(d / "out.exr"));
    // validate compiles the shaders: what render would reject, validate rejects.
    graph("empty.json", "", "");
    expectNamedError(runLoom(d, "validate empty.json"), {"empty.json", "'shader' is empty"});
    writeFile(d / "syntax.comp",
              "#version 460\nlayout(local_size_x = 8) in;\n"
              "void main() { int x = ; }\n");
    graph("syntax.json", "syntax.comp", "");
    expectNamedError(runLoom(d, "validate syntax.json"), {"syntax.json", "syntax.comp:3"});
}

// The GPU watchdog: a shader that never terminates ends the run after --gpu-timeout with code 2,
// naming the pass that was running (not the one before it), and writes no image.
TEST(BadInput, GpuWatchdogNamesThePassThatDoesNotTerminate) {
    TempDir d("loom-bad");
    writeFile(d / "fill.comp",
              "#version 460\nlayout(local_size_x = 8, local_size_y = 8) in;\n"
              "layout(rgba32f) uniform writeonly image2D outImage;\n"
              "void main() { imageStore(outImage, ivec2(gl_GlobalInvocationID.xy), vec4(0)); }\n");
    // llvmpipe ends every loop after 65535 iterations (its own loop limiter), so no loop runs
    // forever there; 4M invocations of a 1M-step loop stand in for one that does (minutes).
    writeFile(d / "spin.comp",
              "#version 460\nlayout(local_size_x = 8, local_size_y = 8) in;\n"
              "layout(rgba32f) uniform readonly image2D inImage;\n"
              "layout(rgba32f) uniform writeonly image2D outImage;\n"
              "void main() {\n  ivec2 p = ivec2(gl_GlobalInvocationID.xy);\n"
              "  float x = imageLoad(inImage, p % 8).x + float(p.x);\n"
              "  for (uint a = 0u; a != 1000000u; ++a) x = fract(sin(x) * 43758.5453 + float(a));\n"
              "  imageStore(outImage, p, vec4(x));\n}\n");
    writeFile(d / "spin.json", R"({"name": "spin", "passes": [
  {"name": "fill", "type": "ComputePass", "params": {"shader": "fill.comp",
    "outputs": {"out": {"glsl": "outImage", "format": "rgba32f"}}}},
  {"name": "spin", "type": "ComputePass", "params": {"shader": "spin.comp",
    "dispatch": [2048, 2048, 1], "inputs": {"in": {"glsl": "inImage", "format": "rgba32f"}},
    "outputs": {"out": {"glsl": "outImage", "format": "rgba32f"}}}}],
  "edges": [["fill.out", "spin.in"]], "outputs": ["spin.out"]})");
    auto start = std::chrono::steady_clock::now();
    Result r = runLoom(d, "render spin.json --gpu-timeout 3" + kSmall);
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    expectNamedError(r, {"GPU watchdog", "3 s", "pass 'spin' (ComputePass) was running"});
    EXPECT_EQ(r.err.find("pass 'fill'"), std::string::npos) << r.err;
    EXPECT_LT(seconds, 100.0) << "the 120 s test timeout, not the watchdog, ended the run";
    EXPECT_FALSE(std::filesystem::exists(d / "out.exr"));
    // The environment variable sets the same watchdog for loom run.
    writeFile(d / "spin.lua",
              "local r = loom.renderer{graph = 'spin.json', width = 8, height = 8}\nr:frame()\n");
    r = runLoom(d, "run spin.lua", "LOOM_GPU_TIMEOUT=3");
    expectNamedError(r, {"GPU watchdog", "pass 'spin' (ComputePass) was running"});
    expectNamedError(runLoom(d, "render spin.json --gpu-timeout -1" + kSmall), {"--gpu-timeout"});
}

// A failed write leaves the old file as it was: full disk (a file-size limit stands in for
// it), /dev/full, a path that cannot be a file. Paths are checked before the render.
TEST(BadInput, FailedWritesNeverDestroyAGoodFile) {
    TempDir d("loom-bad");
    std::string scene = " --scene '" + kSource + "/scenes/cornell_box.json' --width 64 --height 64";
    ASSERT_EQ(runLoom(d, std::string("render ") + kGraph + scene + " --out good.png").exitCode, 0);
    std::string good = readFile(d / "good.png");
    ASSERT_GT(good.size(), 4096u);
    for (const char* file : {"good.png", "good.exr"}) {
        if (std::string(file) == "good.exr") {
            ASSERT_EQ(
                runLoom(d, std::string("render ") + kGraph + scene + " --out good.exr").exitCode,
                0);
        }
        std::string before = readFile(d / file);
        Result r = runLoom(d, std::string("render ") + kGraph + scene + " --seed 3 --out " + file,
                           "ulimit -f 2;");
        expectNamedError(r, {file});
        EXPECT_TRUE(readFile(d / file) == before) << file << " was changed by a failed write";
    }
    EXPECT_TRUE(readFile(d / "good.png") == good);
    // No temporary files are left behind.
    for (auto& e : std::filesystem::directory_iterator(d.path()))
        EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();

    writeFile(d / "csv.lua", "loom.write_csv('/dev/full', {{a = 1}})\n");
    expectNamedError(runLoom(d, "run csv.lua"), {"csv.lua:1", "/dev/full", "No space left"});
    writeFile(d / "json.lua", "loom.write_json('/dev/full', {a = 1})\n");
    expectNamedError(runLoom(d, "run json.lua"), {"json.lua:1", "/dev/full"});
    writeFile(d / "img.lua", "loom.new_image(256, 256):write(loom.args[1])\n");
    ASSERT_EQ(runLoom(d, "run img.lua small.exr").exitCode, 0);
    std::string small = readFile(d / "small.exr");
    Result img = runLoom(d, "run img.lua small.exr", "ulimit -f 1;");
    expectNamedError(img, {"img.lua:1", "small.exr"});
    EXPECT_TRUE(readFile(d / "small.exr") == small);

    // An output under a regular file fails before rendering, in well under the render's time.
    expectNamedError(runLoom(d, std::string("render ") + kGraph + scene +
                                    " --frames 100000 --out good.png/x.png"),
                     {"good.png/x.png", "cannot create the directory"});
}

}  // namespace
