// The `loom` Lua module and `loom run` / `loom merge`: every API function in-process (on the
// shared lavapipe context), error messages (names, script:line, traceback, exit 2), the
// run_for_ms budget, sharded sweeps and their merge, and every shipped script on a tiny scene.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <set>

#include "core/image/Image.h"
#include "core/script/Csv.h"
#include "core/script/LuaBindings.h"
#include "core/util/Error.h"
#include "core/util/JsonSource.h"
#include "tests/support/GpuSupport.h"

using namespace loom;
using namespace loom::test;
using loom::script::LuaRuntime;

namespace {

const std::string kSource = LOOM_SOURCE_DIR;

std::string luaQuote(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out + "\"";
}

class LuaApi : public ::testing::Test {
protected:
    TempDir tmp{"loom-lua"};
    std::string error;

    std::unique_ptr<LuaRuntime> runtime(std::vector<std::string> args = {}, uint32_t shard = 0,
                                        uint32_t shards = 1) {
        LuaRuntime::Options o;
        o.gpu = gpuContext();
        o.cacheDir = gpuCacheDir();
        o.args = std::move(args);
        o.shardIndex = shard;
        o.shardCount = shards;
        o.printErrors = false;
        auto lua = std::make_unique<LuaRuntime>(o);
        // Globals for the tests' Lua code (a separate chunk keeps line numbers exact).
        EXPECT_EQ(lua->runString("TMP = " + luaQuote(tmp.str()) + "\nSRC = " + luaQuote(kSource)),
                  0);
        return lua;
    }
    // Runs `code` as chunk "test" (messages read "test:LINE: ..."); returns the exit code.
    int run(const std::string& code, std::vector<std::string> args = {}, uint32_t shard = 0,
            uint32_t shards = 1) {
        auto lua = runtime(std::move(args), shard, shards);
        int rc = lua->runString(code, "=test");
        error = lua->lastError();
        return rc;
    }
};

// A pcall helper every error test uses: expect(fn, "substring", ...) checks the message.
const std::string kExpectError = R"lua(
function expect_error(fn, ...)
  local ok, err = pcall(fn)
  assert(not ok, "expected an error")
  for _, s in ipairs({...}) do
    assert(err:find(s, 1, true), "message '" .. err .. "' lacks '" .. s .. "'")
  end
  return err
end
)lua";

// ---------------------------------------------------------------------------------------------
// Renderer, parameters

TEST_F(LuaApi, RendererFramesAndParameters) {
    int rc = run(kExpectError + R"lua(
local r = loom.renderer{graph = "graphs/pt.json", scene = "scenes/cornell_box.json",
                        width = 16, height = 16, seed = 3}
assert(tostring(r):find("loom.Renderer 'pt' 16x16"))
assert(r:width() == 16 and r:height() == 16)
r:frame()
r:frames(2)
assert(r:frame_count() == 3)
-- Integers stay integers, floats floats; validation normalises int -> float parameters.
assert(math.type(r:get("pt.samplesPerPixel")) == "integer" and r:get("pt.samplesPerPixel") == 1)
r:set("pt.samplesPerPixel", 2)
assert(r:get("pt.samplesPerPixel") == 2)
r:set("tm.exposure", 1)
assert(math.type(r:get("tm.exposure")) == "float" and r:get("tm.exposure") == 1.0)
r:set("pt.strategy", "bsdf")
assert(r:get("pt.strategy") == "bsdf")
r:set("pt.motionBlur", false)
assert(r:get("pt.motionBlur") == false)
local p = r:params()
local spp = p["pt.samplesPerPixel"]
assert(spp.type == "int" and spp.value == 2 and spp.default == 1)
assert(spp.min == 1 and spp.max == 4096 and spp.doc:find("paths per pixel"))
assert(p["pt.strategy"].type == "enum" and #p["pt.strategy"].choices == 3)
assert(p["pt.strategy"].choices[1] == "mis")
assert(p["tm.exposure"].value == 1.0 and p["tm.srgb"].type == "bool")
local passes = r:passes()
assert(#passes == 4 and passes[1].name == "gbuf" and passes[1].type == "GBuffer")
assert(passes[2].name == "pt" and passes[2].type == "PathTracer")
assert(r:outputs()[1] == "tm.output")
r:frame()
r:reset()
r:set_seed(9)
r:resize(8, 8)
r:frame()
assert(r:image("tm.output"):width() == 8)
r:close()
assert(tostring(r):find("closed"))
expect_error(function() r:frame() end, "this renderer was closed")
-- Parameters at creation.
local r2 = loom.renderer{graph = "graphs/pt.json", scene = "scenes/cornell_box.json",
                         width = 8, height = 8, params = {["pt.maxBounces"] = 2}}
assert(r2:get("pt.maxBounces") == 2)
)lua");
    EXPECT_EQ(rc, 0) << error;
}

TEST_F(LuaApi, VectorAndJsonConversions) {
    int rc = run(kExpectError + R"lua(
local r = loom.renderer{graph = "graphs/hello_compute.json", width = 16, height = 16}
r:set("scene.sunDirection", {0, 1, 0.5})
local v = r:get("scene.sunDirection")
assert(#v == 3 and v[1] == 0 and v[2] == 1 and v[3] == 0.5)
expect_error(function() r:set("scene.sunDirection", {1, 2}) end,
             "r:set('scene.sunDirection')", "an array of 3 numbers")
expect_error(function() r:set("scene.sunDirection", {1, nil, 3}) end, "array table has holes")
expect_error(function() r:set("scene.sunDirection", {1, 2, x = 3}) end, "mixes array elements")
expect_error(function() r:set("scene.sunDirection", print) end, "cannot be converted to JSON")
r:set("scene.sunIntensity", 4)
assert(r:get("scene.sunIntensity") == 4.0)
r:frame()
-- JSON text and files.
local t = loom.json_decode('{"a": 1, "b": [1, 2.5, "x"], "c": {"d": true}, "e": {}}')
assert(math.type(t.a) == "integer" and t.b[2] == 2.5 and t.b[3] == "x" and t.c.d == true)
assert(next(t.e) == nil)
assert(loom.json_encode({1, 2, 3}) == "[1,2,3]")
assert(loom.json_encode({a = 1.5}) == '{"a":1.5}')
loom.write_json(TMP .. "/v.json", {n = 3, f = 0.25, list = {"a", "b"}, nested = {ok = false}})
local back = loom.read_json(TMP .. "/v.json")
assert(math.type(back.n) == "integer" and back.f == 0.25 and back.list[2] == "b")
assert(back.nested.ok == false)
expect_error(function() loom.json_decode("{bad") end, "JSON syntax error")
expect_error(function() loom.read_json(TMP .. "/nope.json") end, "JSON file not found")
)lua");
    EXPECT_EQ(rc, 0) << error;
}

TEST_F(LuaApi, ParameterAndInputErrorsNameWhatIsValid) {
    int rc = run(kExpectError + R"lua(
local r = loom.renderer{graph = "graphs/pt.json", scene = "scenes/cornell_box.json",
                        width = 8, height = 8}
expect_error(function() r:set("pt.sampelsPerPixel", 4) end,
             "test:", "PathTracer 'pt' has no parameter 'sampelsPerPixel'",
             "valid parameters: samplesPerPixel, maxBounces")
expect_error(function() return r:get("pt.nope") end, "no parameter 'nope'", "valid parameters:")
expect_error(function() r:set("ptx.samplesPerPixel", 4) end,
             "no pass named 'ptx'", "passes: gbuf, pt, accum, tm")
expect_error(function() r:set("samplesPerPixel", 4) end, "expected 'pass.param'")
expect_error(function() r:set("pt.samplesPerPixel", "four") end,
             "expects an integer", "string")
expect_error(function() r:set("pt.samplesPerPixel", 0) end, "out of range [1, 4096]")
expect_error(function() r:set("pt.strategy", "path") end, "is not one of: mis, bsdf, nee")
expect_error(function() r:set("pt.samplesPerPixel") end, "missing the value")
expect_error(function() r:set(42, 1) end, "must be a string, got number 42")
expect_error(function() r.frame() end, "call it as r:frame(...) with ':'")
expect_error(function() r:frames(-1) end, "the frame count must be in [0")
expect_error(function() r:image("pt.color") end,
             "'pt.color' is not a marked output", "marked outputs: tm.output, accum.output")
expect_error(function() loom.renderer{graph = "graphs/nope.json"} end,
             "graph file not found: 'graphs/nope.json'")
expect_error(function() loom.renderer{graph = "graphs/pt.json", scene = "nope.json"} end,
             "scene file not found: 'nope.json'")
expect_error(function() loom.renderer{graph = "graphs/pt.json", widht = 8} end,
             "unknown key 'widht'", "valid keys: graph, scene, width, height")
expect_error(function() loom.renderer{scene = "scenes/cornell_box.json"} end, "'graph'")
expect_error(function() loom.renderer("graphs/pt.json") end, "expects a table")
expect_error(function() loom.renderer{graph = "graphs/pt.json", width = 0} end,
             "'width' must be in [1, 16384]")
expect_error(function() loom.read_image(TMP .. "/missing.exr") end, "image file not found")
-- A script survives every error: the renderer still renders.
r:frame()
assert(r:image("tm.output"):width() == 8)
)lua");
    EXPECT_EQ(rc, 0) << error;
}

// ---------------------------------------------------------------------------------------------
// Errors that end the script: exit 2, script:line, traceback

TEST_F(LuaApi, RuntimeErrorReportsLineAndTraceback) {
    int rc =
        run("local x = 1\nlocal r = loom.renderer{graph = 'graphs/pt.json', width = 8, "
            "height = 8}\nr:set('pt.nope', 1)\n");
    EXPECT_EQ(rc, 2);
    EXPECT_NE(error.find("test:3: r:set('pt.nope'): PathTracer 'pt' has no parameter 'nope'"),
              std::string::npos)
        << error;
    EXPECT_NE(error.find("stack traceback:"), std::string::npos) << error;

    EXPECT_EQ(run("local function f()\n  error('boom')\nend\nf()\n"), 2);
    EXPECT_NE(error.find("test:2: boom"), std::string::npos) << error;
    EXPECT_NE(error.find("in local 'f'"), std::string::npos) << error;

    EXPECT_EQ(run("error({})"), 2);
    EXPECT_NE(error.find("(error object is a table value)"), std::string::npos) << error;

    // A successful run returns 0, or the integer the script returns.
    EXPECT_EQ(run("return 7"), 7);
    EXPECT_EQ(run("local a = 1"), 0);
    EXPECT_EQ(error, "");
}

TEST_F(LuaApi, SyntaxErrorAndMissingScript) {
    auto lua = runtime();
    EXPECT_EQ(lua->runString("local x = = 1", "=bad.lua"), 2);
    EXPECT_NE(lua->lastError().find("bad.lua:1:"), std::string::npos) << lua->lastError();
    EXPECT_EQ(lua->runFile(tmp / "does_not_exist.lua"), 2);
    EXPECT_NE(lua->lastError().find("cannot open"), std::string::npos) << lua->lastError();
    // The runtime stays usable after errors.
    EXPECT_EQ(lua->runString("assert(loom.version)"), 0) << lua->lastError();
}

TEST_F(LuaApi, ScriptFilesFindModulesAndArguments) {
    writeFile(tmp / "lib/helper.lua", "return {answer = 42}\n");
    writeFile(tmp / "lib/main.lua",
              "local h = require('helper')\nassert(h.answer == 42)\nassert(arg[1] == 'x=1')\n"
              "assert(select(1, ...) == 'x=1')\nreturn loom.arg('x', 0) + 1\n");
    auto lua = runtime({"x=1"});
    EXPECT_EQ(lua->runFile(tmp / "lib/main.lua"), 2) << lua->lastError();
}

// ---------------------------------------------------------------------------------------------
// Graph editing

TEST_F(LuaApi, GraphEditing) {
    int rc = run(kExpectError + R"lua(
local r = loom.renderer{graph = "graphs/hello_compute.json", width = 16, height = 16}
r:add_pass("ToneMap", "tm2", {exposure = 2.0, operator = "clamp"})
r:connect("accum.output", "tm2.input")
r:mark_output("tm2.output")
r:frames(2)
local bright = r:image("tm2.output"):mean()
local normal = r:image("tm.output"):mean()
assert(bright > normal, "exposure +2 should brighten")
r:save_graph(TMP .. "/edited/graph.json")
local r2 = loom.renderer{graph = TMP .. "/edited/graph.json", width = 16, height = 16}
assert(r2:get("tm2.exposure") == 2.0 and r2:get("tm2.operator") == "clamp")
local outs = r2:outputs()
assert(outs[#outs] == "tm2.output")
r2:frame()
-- Errors name what exists.
expect_error(function() r:connect("accum.output", "tm2.nope") end, "has no input 'nope'",
             "inputs: input")
expect_error(function() r:add_pass("NoSuchPass", "x") end, "NoSuchPass")
expect_error(function() r:add_pass("ToneMap", "tm2") end, "already exists")
expect_error(function() r:add_pass("ToneMap", "tm3", {gain = 1}) end, "no parameter 'gain'")
expect_error(function() r:remove_pass("nope") end, "no pass named 'nope'")
expect_error(function() r:disconnect("a.b", "c.d") end, "no edge a.b -> c.d")
expect_error(function() r:mark_output("tm2.nope") end, "no output port 'nope'")
-- Undo the edit: the original graph renders again.
r:unmark_output("tm2.output")
r:disconnect("accum.output", "tm2.input")
r:remove_pass("tm2")
assert(#r:passes() == 3 and #r:outputs() == 2)
r:frame()
expect_error(function() r:image("tm2.output") end, "not a marked output")
)lua");
    EXPECT_EQ(rc, 0) << error;
}

// ---------------------------------------------------------------------------------------------
// Camera and animation

TEST_F(LuaApi, CameraAndCameraPath) {
    int rc = run(kExpectError + R"lua(
local function near(a, b) return math.abs(a - b) < 1e-3 end
local r = loom.renderer{graph = "graphs/pt.json", scene = "scenes/cornell_box.json",
                        width = 16, height = 16}
local c = r:camera()
assert(near(c.origin[1], 0) and near(c.origin[2], 1) and near(c.origin[3], 6.8), "origin")
assert(near(c.fov, 19.5) and near(c.up[2], 1) and near(c.target[3], 0), "fov/up/target")
r:frames(2)
local before = {r:image("accum.output"):mean()}
r:camera{origin = {0, 1, 3}, fov = 60}
c = r:camera()
assert(near(c.origin[3], 3) and near(c.fov, 60) and near(c.target[2], 1))
r:frame()
local after = {r:image("accum.output"):mean()}
assert(math.abs(after[1] - before[1]) > 1e-4, "a new camera changes the image")
assert(r:frame_count() == 3)

loom.write_json(TMP .. "/path.json", {
  {time = 0, origin = {0, 1, 6.8}, target = {0, 1, 0}, fov = 30},
  {time = 10, origin = {2, 1, 6.8}, fov = 40}})
local n, last = r:camera_path(TMP .. "/path.json")
assert(n == 2 and last == 10)
r:set_time(5)
assert(r:time() == 5)
c = r:camera()
assert(near(c.origin[1], 1) and near(c.fov, 35), "interpolated keyframe")
r:frame()

loom.write_json(TMP .. "/bad_path.json", {{time = 1}, {time = 0}})
expect_error(function() r:camera_path(TMP .. "/bad_path.json") end,
             "bad_path.json:", "keyframe times must increase")
loom.write_json(TMP .. "/bad_key.json", {{time = 0, eye = {1, 2, 3}}})
expect_error(function() r:camera_path(TMP .. "/bad_key.json") end, "unknown key 'eye'")
expect_error(function() r:camera_path(TMP .. "/none.json") end, "camera path file not found")
expect_error(function() r:camera{origin = {0, 1}} end, "'origin' must be an array of 3 numbers")
expect_error(function() r:camera{fov = 200} end, "'fov' must be in (0, 180)")
expect_error(function() r:camera{eye = {0, 0, 0}} end, "unknown key 'eye'")
r:shutter(0, 2)
local so, sc = r:shutter()
assert(so == 0 and sc == 2, "shutter set")
assert(near(r:camera().origin[1], 1), "the shutter keeps the camera path")
expect_error(function() r:shutter(1, 0) end, "open <= close")

local h = loom.renderer{graph = "graphs/hello_compute.json", width = 8, height = 8}
expect_error(function() h:camera() end, "has no scene")
)lua");
    EXPECT_EQ(rc, 0) << error;
}

// ---------------------------------------------------------------------------------------------
// Images and metrics

TEST_F(LuaApi, ImagesAndMetrics) {
    int rc = run(kExpectError + R"lua(
local function near(a, b) return math.abs(a - b) < 1e-9 end
local a = loom.new_image(4, 2, 0.5, 0.5, 0.5)
local b = loom.new_image(4, 2, 1, 1, 1)
assert(a:width() == 4 and a:height() == 2 and a:channels() == 4)
assert(tostring(a) == "loom.Image 4x2 (4 channels)")
assert(near(loom.metrics.mse(a, b), 0.25))
assert(near(loom.metrics.rmse(a, b), 0.5))
assert(near(loom.metrics.relmse(a, b), 0.25 / 1.01))
assert(near(loom.metrics.mape(a, b), 0.5 / 1.01))
assert(near(loom.metrics.mape(a, b, 0), 0.5))
a:set(1, 0, 2, 3, 4)
local r_, g, b_, al = a:get(1, 0)
assert(r_ == 2 and g == 3 and b_ == 4 and al == 1)
local mr, mg, mb = a:mean()
assert(near(mr, (0.5 * 7 + 2) / 8) and near(mb, (0.5 * 7 + 4) / 8))
local c = a:crop(1, 0, 2, 1)
assert(c:width() == 2 and c:height() == 1 and select(1, c:get(0, 0)) == 2)
a:write(TMP .. "/a.exr")
local a2 = loom.read_image(TMP .. "/a.exr")
assert(loom.metrics.mse(a, a2) == 0, "EXR round trip is exact")
local e = loom.metrics.error_image(a, b, "mape")
assert(e:width() == 4 and e:height() == 2)
e:write(TMP .. "/err.png")
expect_error(function() a:get(4, 0) end, "pixel (4, 0) is outside the 4x2 image")
expect_error(function() a:crop(3, 0, 2, 1) end, "exceeds the 4x2 image")
expect_error(function() loom.metrics.mse(a, loom.new_image(2, 2)) end,
             "image is 4x2 but reference is 2x2")
expect_error(function() loom.metrics.relmse(a, 3) end, "must be an image, got number 3")
expect_error(function() loom.metrics.error_image(a, b, "nope") end, "unknown metric 'nope'")
expect_error(function() a:write(TMP .. "/noext") end, "needs an extension")

-- Images from a renderer.
local r = loom.renderer{graph = "graphs/pt.json", scene = "scenes/cornell_box.json",
                        width = 16, height = 16}
r:frames(2)
local img = r:image("accum.output")
assert(img:width() == 16 and img:height() == 16)
local lr, lg, lb = img:mean()
assert(lr > 0 and lg > 0 and lb > 0, "the Cornell box is lit")
r:capture("tm.output", TMP .. "/tm.png")
local png = loom.read_image(TMP .. "/tm.png")
assert(png:width() == 16)
)lua");
    EXPECT_EQ(rc, 0) << error;
    uint32_t w = 0, h = 0;
    readImageSize(tmp / "err.png", w, h);
    EXPECT_EQ(w, 4u);
}

// ---------------------------------------------------------------------------------------------
// Timings, statistics, run_for_ms

TEST_F(LuaApi, TimingsStatsAndRunForMs) {
    int rc = run(kExpectError + R"lua(
local r = loom.renderer{graph = "graphs/pt.json", scene = "scenes/cornell_box.json",
                        width = 16, height = 16}
r:frame()
local t = r:timings()
assert(#t.passes == 4 and t.passes[2].pass == "pt" and t.passes[4].pass == "tm")
assert(t.frame_ms > 0 and t.passes[2].ms > 0)
local s = r:stats()
assert(s["pt.rays"] and s["pt.rays"] > 0, "PathTracer counts rays")
-- The loop stops on the frame that crosses the budget: spent >= budget, and without that last
-- frame it was still below the budget.
for _, frames in ipairs({1, 5, 20}) do
  local budget = frames * r:timings().frame_ms
  local before = r:frame_count()
  local n, spent = r:run_for_ms(budget)
  local last = r:timings().frame_ms
  assert(n >= 1 and r:frame_count() == before + n)
  assert(spent >= budget, string.format("spent %g < budget %g", spent, budget))
  assert(spent - last < budget, string.format("overshoot: %g - %g >= %g", spent, last, budget))
end
assert(r:run_for_ms(0) == 0)
expect_error(function() r:run_for_ms(-1) end, "must be a finite number >= 0")
expect_error(function() r:run_for_ms(1 / 0) end, "must be a finite number >= 0")
)lua");
    EXPECT_EQ(rc, 0) << error;
}

// ---------------------------------------------------------------------------------------------
// CSV, plots

TEST_F(LuaApi, CsvWriteRead) {
    int rc = run(kExpectError + R"lua(
local n = loom.write_csv(TMP .. "/t.csv", {
  {name = "b, c", x = 1.5, index = 2},
  {name = 'say "hi"', y = true, index = 1},
  {name = "z", x = 0.1, index = 3, z = 7}})
assert(n == 3)
local rows = loom.read_csv(TMP .. "/t.csv")
assert(#rows == 3 and rows[1].index == 2 and rows[1].name == "b, c" and rows[1].x == 1.5)
assert(rows[2].name == 'say "hi"' and rows[2].y == "true" and rows[2].x == nil)
assert(rows[3].x == 0.1 and math.type(rows[3].z) == "integer")
loom.write_csv(TMP .. "/cols.csv", {{b = 1, a = 2, c = 3}}, {columns = {"c", "b"}})
loom.write_csv(TMP .. "/empty.csv", {})
expect_error(function() loom.write_csv(TMP .. "/x.csv", {{a = {1}}}) end,
             "rows[1].a is a table")
expect_error(function() loom.write_csv(TMP .. "/x.csv", {1}) end, "rows[1] must be a table")
expect_error(function() loom.write_csv(TMP .. "/x.csv", {{1, 2}}) end, "non-string key")
)lua");
    ASSERT_EQ(rc, 0) << error;
    // Header: index first, then alphabetical; shortest round-trip numbers; RFC 4180 quoting.
    EXPECT_EQ(readFile(tmp / "t.csv"),
              "index,name,x,y,z\n2,\"b, c\",1.5,,\n1,\"say \"\"hi\"\"\",,true,\n3,z,0.1,,7\n");
    EXPECT_EQ(readFile(tmp / "cols.csv"), "c,b,a\n3,1,2\n");
    EXPECT_EQ(readFile(tmp / "empty.csv"), "");
}

TEST_F(LuaApi, PlotWritesSvgAndPng) {
    int rc = run(kExpectError + R"lua(
local svg, png = loom.plot{path = TMP .. "/plots/err.png", title = "Error vs time",
  x_label = "GPU time (ms)", y_label = "relMSE", log_x = true, log_y = true,
  series = {{name = "mis", x = {10, 20, 40, 80}, y = {0.1, 0.05, 0.025, 0.0125}},
            {name = "bsdf", x = {10, 20, 40, 80}, y = {0.3, 0.16, 0.07, 0.04}}}}
assert(svg == TMP .. "/plots/err.svg" and png == TMP .. "/plots/err.png")
local img = loom.read_image(png)
assert(img:width() == 800 and img:height() == 520)
loom.plot{path = TMP .. "/plots/lin", series = {{x = {1, 2, 3}, y = {3, 1, 2}}}, width = 400,
          height = 300}
expect_error(function() loom.plot{path = TMP .. "/p", series = {{x = {1, 2}, y = {1}}}} end,
             "2 x values but 1 y values")
expect_error(function() loom.plot{path = TMP .. "/p", log_y = true,
                                  series = {{x = {1, 2}, y = {0, -1}}}} end, "no data point")
expect_error(function() loom.plot{series = {}} end, "'path' is required")
expect_error(function() loom.plot{path = TMP .. "/p", series = {}, colour = 1} end,
             "unknown key 'colour'")
)lua");
    ASSERT_EQ(rc, 0) << error;
    std::string svg = readFile(tmp / "plots/err.svg");
    EXPECT_EQ(svg.rfind("<svg", 0), 0u);
    for (const char* s :
         {"Error vs time", "GPU time (ms)", "relMSE", ">mis<", ">bsdf<", "polyline"})
        EXPECT_NE(svg.find(s), std::string::npos) << s;
    // The PNG is not blank: it has the white background, dark text and coloured lines.
    ImageData png = readImage(tmp / "plots/err.png");
    size_t dark = 0, coloured = 0;
    for (uint32_t y = 0; y < png.height; ++y)
        for (uint32_t x = 0; x < png.width; ++x) {
            float r = png.at(x, y, 0), g = png.at(x, y, 1), b = png.at(x, y, 2);
            if (r < 0.3f && g < 0.3f && b < 0.3f) ++dark;
            if (std::max({r, g, b}) - std::min({r, g, b}) > 0.3f) ++coloured;
        }
    EXPECT_GT(dark, 500u);
    EXPECT_GT(coloured, 500u);
    EXPECT_TRUE(fs::exists(tmp / "plots/lin.png"));
}

// ---------------------------------------------------------------------------------------------
// Arguments, progress, sweeps

TEST_F(LuaApi, ScriptArguments) {
    int rc = run(
        kExpectError + R"lua(
assert(loom.args[1] == "width=16" and loom.args.width == "16" and loom.args[7] == "pos")
assert(loom.arg("width", 8) == 16 and math.type(loom.arg("width", 8)) == "integer")
assert(loom.arg("frames", 1) == 3)
assert(loom.arg("scale", 1.0) == 0.5)
assert(loom.arg("flag", false) == true)
assert(loom.arg("name", "x") == "abc")
assert(loom.arg("missing", 7) == 7 and loom.arg("missing") == nil)
local v = loom.arg("values", {1})
assert(#v == 3 and v[3] == 4 and math.type(v[1]) == "integer")
expect_error(function() return loom.arg("name", 1.0) end,
             "script argument 'name' expects a number, got 'abc'")
expect_error(function() return loom.arg("scale", 1) end, "expects an integer")
expect_error(function() return loom.arg("name", true) end, "expects a boolean")
assert(loom.shard.index == 0 and loom.shard.count == 1)
)lua",
        {"width=16", "--frames", "3", "--scale=0.5", "--flag", "name=abc", "pos", "values=1,2,4"});
    EXPECT_EQ(rc, 0) << error;
}

TEST_F(LuaApi, ProgressIsSilentWithoutTerminal) {
    const std::string code = R"lua(
for i = 0, 3 do loom.progress(i, 3, "work") end
loom.progress(1, 2)
)lua";
    unsetenv("LOOM_PROGRESS");
    if (!isatty(STDERR_FILENO)) {
        testing::internal::CaptureStderr();
        EXPECT_EQ(run(code), 0) << error;
        EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    }
    setenv("LOOM_PROGRESS", "1", 1);
    testing::internal::CaptureStderr();
    EXPECT_EQ(run(code), 0) << error;
    std::string err = testing::internal::GetCapturedStderr();
    unsetenv("LOOM_PROGRESS");
    EXPECT_NE(err.find("work [......"), std::string::npos) << err;
    EXPECT_NE(err.find("3/3 100%"), std::string::npos) << err;
    EXPECT_NE(err.find("ETA done"), std::string::npos) << err;
    EXPECT_EQ(err.find("\x1b["), std::string::npos) << "no terminal codes when not a TTY";
}

TEST_F(LuaApi, SweepShardsAreDisjointAndCoverAllValues) {
    const std::string code = R"lua(
local got = {}
for index, value in loom.sweep{name = "s", values = {10, 20, 30, 40, 50, 60, 70}} do
  assert(value == index * 10)
  got[#got + 1] = index
end
loom.write_json(string.format("%s/shard_%d_of_%d.json", TMP, loom.shard.index, loom.shard.count),
                got)
)lua";
    for (uint32_t count : {1u, 2u, 3u, 10u}) {
        std::multiset<int> all;
        for (uint32_t i = 0; i < count; ++i) {
            ASSERT_EQ(run(code, {}, i, count), 0) << error;
            json got = JsonSource::load(tmp / ("shard_" + std::to_string(i) + "_of_" +
                                               std::to_string(count) + ".json"))
                           .root();
            for (auto& idx : got) {
                EXPECT_EQ((idx.get<int>() - 1) % int(count), int(i)) << "round robin";
                all.insert(idx.get<int>());
            }
        }
        EXPECT_EQ(all, (std::multiset<int>{1, 2, 3, 4, 5, 6, 7})) << count << " shards";
    }
    EXPECT_EQ(run("loom.sweep{name = 'x', values = {}}"), 2);
    EXPECT_NE(error.find("'values' must be a non-empty array"), std::string::npos) << error;
}

TEST(LuaShard, ParseShard) {
    uint32_t i = 9, n = 9;
    script::parseShard("1/4", i, n);
    EXPECT_EQ(i, 1u);
    EXPECT_EQ(n, 4u);
    for (const char* bad : {"4/4", "1", "a/b", "-1/2", "1/0", "1/2x", ""})
        EXPECT_THROW(script::parseShard(bad, i, n), UserError) << bad;
    LuaRuntime::Options o;
    o.shardIndex = 2;
    o.shardCount = 2;
    EXPECT_THROW(LuaRuntime{o}, UserError);
}

TEST(LuaCsv, MergeSortsByIndexAndChecksHeaders) {
    TempDir tmp("loom-csv");
    writeFile(tmp / "a.csv", "index,v\n3,c\n1,a\n");
    writeFile(tmp / "b.csv", "index,v\n2,\"b,b\"\n");
    writeFile(tmp / "empty.csv", "");
    writeFile(tmp / "other.csv", "index,w\n4,d\n");
    auto merged = script::mergeCsv({tmp / "a.csv", tmp / "empty.csv", tmp / "b.csv"});
    script::writeCsv(tmp / "m.csv", merged);
    EXPECT_EQ(readFile(tmp / "m.csv"), "index,v\n1,a\n2,\"b,b\"\n3,c\n");
    try {
        script::mergeCsv({tmp / "a.csv", tmp / "other.csv"});
        FAIL() << "expected a header mismatch";
    } catch (const UserError& e) {
        EXPECT_NE(std::string(e.what()).find("other.csv: header 'index,w' differs"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_THROW(script::readCsv(tmp / "none.csv"), UserError);
}

// Parts carry "# loom-sweep id=ID shard=I/N": one sweep, every shard once, none missing.
TEST(LuaCsv, MergeOfPartsChecksTheSweep) {
    TempDir tmp("loom-csv");
    auto part = [&](const std::string& name, const std::string& id, int i, int n,
                    const std::string& body) {
        writeFile(tmp / name, "# loom-sweep id=" + id + " shard=" + std::to_string(i) + "/" +
                                  std::to_string(n) + "\n" + body);
    };
    part("a0.csv", "abc", 0, 3, "index,v\n1,x\n");
    part("a1.csv", "abc", 1, 3, "");  // a shard that owned no values
    part("a2.csv", "abc", 2, 3, "index,v\n3,z\n");
    part("b1.csv", "xyz", 1, 3, "index,v\n2,y\n");
    writeFile(tmp / "plain.csv", "index,v\n2,y\n");
    auto merged = script::mergeCsv({tmp / "a2.csv", tmp / "a0.csv", tmp / "a1.csv"});
    EXPECT_FALSE(merged.sweep.has_value());
    script::writeCsv(tmp / "m.csv", merged);
    EXPECT_EQ(readFile(tmp / "m.csv"), "index,v\n1,x\n3,z\n");
    auto expectError = [&](std::vector<std::string> files, const std::string& fragment) {
        try {
            script::mergeCsv(files);
            ADD_FAILURE() << "expected: " << fragment;
        } catch (const UserError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        }
    };
    expectError({tmp / "a0.csv", tmp / "b1.csv", tmp / "a2.csv"},
                "parts of different sweeps do not merge");
    expectError({tmp / "a0.csv", tmp / "a2.csv"}, "shard(s) 1 of 3 missing");
    expectError({tmp / "a0.csv", tmp / "a0.csv", tmp / "a1.csv", tmp / "a2.csv"},
                "shard 0/3 is also in");
    expectError({tmp / "a0.csv", tmp / "plain.csv"}, "not a part of a sweep");
    writeFile(tmp / "bad.csv", "# loom-sweep id=abc shard=3/3\nindex\n");
    expectError({tmp / "bad.csv"}, "bad.csv:1: malformed sweep line");
    EXPECT_EQ(script::csvPartPath("out/x/abl.csv", 7), "out/x/abl.PART-7.csv");
}

// ---------------------------------------------------------------------------------------------
// `loom run` / `loom merge` and the shipped scripts (subprocesses)

struct CommandResult {
    int exitCode = -1;
    std::string out, err;
};

// Runs the loom binary in `cwd` with the test's shader cache.
// `env`: NAME=VALUE assignments for the command.
CommandResult runLoom(const std::string& args, const TempDir& cwd, const std::string& env = "") {
    std::string cmd = "cd '" + cwd.str() + "' && " + env + " LOOM_CACHE_DIR='" + gpuCacheDir() +
                      "' LOOM_PROGRESS=0 '" + LOOM_BINARY + "' " + args + " >'" + (cwd / "stdout") +
                      "' 2>'" + (cwd / "stderr") + "'";
    int status = std::system(cmd.c_str());
    CommandResult r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = readFile(cwd / "stdout");
    r.err = readFile(cwd / "stderr");
    return r;
}

std::string script(const std::string& name) {
    return "'" + kSource + "/scripts/" + name + "'";
}

TEST(LoomRun, HelpUsageAndErrors) {
    TempDir tmp("loom-run");
    auto r = runLoom("run --help", tmp);
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_NE(r.out.find("usage: loom run"), std::string::npos);
    EXPECT_EQ(runLoom("merge --help", tmp).exitCode, 0);
    EXPECT_EQ(runLoom("run", tmp).exitCode, 2);
    r = runLoom("run nope.lua", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("script not found: 'nope.lua'"), std::string::npos) << r.err;

    writeFile(tmp / "syntax.lua", "local a = 1\nlocal b = = 2\n");
    r = runLoom("run syntax.lua", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("syntax.lua:2:"), std::string::npos) << r.err;

    writeFile(tmp / "runtime.lua",
              "local r = loom.renderer{graph = 'graphs/pt.json', width = 8, height = 8}\n"
              "print('before')\nr:set('tm.exposur', 1)\nprint('after')\n");
    r = runLoom("run runtime.lua", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.out.find("before"), std::string::npos);
    EXPECT_EQ(r.out.find("after"), std::string::npos);
    EXPECT_NE(r.err.find("runtime.lua:3: r:set('tm.exposur'): ToneMap 'tm' has no parameter "
                         "'exposur'; valid parameters: exposure, operator, srgb"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("stack traceback:"), std::string::npos) << r.err;

    writeFile(tmp / "missing.lua", "loom.read_image('nowhere.exr')\n");
    r = runLoom("run missing.lua", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("missing.lua:1: loom.read_image: image file not found: 'nowhere.exr'"),
              std::string::npos)
        << r.err;

    EXPECT_EQ(runLoom("run syntax.lua --shard 2/2", tmp).exitCode, 2);
    writeFile(tmp / "a.csv", "x\n1\n");
    writeFile(tmp / "b.csv", "y\n1\n");
    r = runLoom("merge out.csv a.csv b.csv", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("header 'y' differs from 'x'"), std::string::npos) << r.err;
    EXPECT_EQ(runLoom("merge out.csv", tmp).exitCode, 2);
}

TEST(LoomRun, CaptureScript) {
    TempDir tmp("loom-run");
    auto r =
        runLoom("run " + script("capture.lua") +
                    " width=16 height=16 frames=2 out=cap pt.samplesPerPixel=2 tm.operator=clamp",
                tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(tmp / "cap/tm_output.png")) << r.out;
    EXPECT_TRUE(fs::exists(tmp / "cap/accum_output.exr")) << r.out;
    r = runLoom("run " + script("capture.lua") +
                    " graph=graphs/hello_compute.json scene= width=16 height=16 frames=2 out=hc",
                tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(tmp / "hc/tm_output.png"));
    r = runLoom("run " + script("capture.lua") + " width=16 height=16 frames=1 pt.nope=1", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("no parameter 'nope'"), std::string::npos) << r.err;
}

TEST(LoomRun, ReferenceScript) {
    TempDir tmp("loom-run");
    auto r = runLoom(
        "run " + script("reference.lua") + " width=16 height=16 frames=2 spp=4 out=ref.exr", tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    ImageData ref = readImage(tmp / "ref.exr");
    EXPECT_EQ(ref.width, 16u);
    EXPECT_TRUE(fs::exists(tmp / "ref.png"));
    EXPECT_NE(r.out.find("2 frames x 4 spp = 8 spp"), std::string::npos) << r.out;
}

TEST(LoomRun, EqualTimeScript) {
    TempDir tmp("loom-run");
    auto r = runLoom("run " + script("equal_time.lua") +
                         " width=16 height=16 budget_ms=8 steps=3 ref_frames=2 ref_spp=8 out=et",
                     tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* s : {"mis 1spp", "mis 4spp", "bsdf 1spp", "relMSE", "MAPE"})
        EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
    script::CsvTable csv = script::readCsv(tmp / "et/equal_time.csv");
    EXPECT_EQ(csv.header, (std::vector<std::string>{"index", "config", "budget_ms", "gpu_ms",
                                                    "frames", "spp", "relmse", "mape"}));
    ASSERT_EQ(csv.rows.size(), 9u);
    for (auto& row : csv.rows) EXPECT_GE(std::stod(row[3]), std::stod(row[2])) << "budget met";
    for (const char* f : {"et/equal_time.png", "et/equal_time.svg", "et/mape.png",
                          "et/mis_1spp.png", "et/bsdf_1spp_relmse.png"})
        EXPECT_TRUE(fs::exists(tmp / f)) << f;
}

TEST(LoomRun, AblationShardsMergeToTheUnshardedRun) {
    TempDir tmp("loom-run");
    std::string common =
        " width=16 height=16 frames=2 values=1,2,3,5,9 ref_frames=2 ref_spp=4"
        " reference=ref.exr";
    auto r = runLoom("run " + script("ablation.lua") + common + " out=all", tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("pt.maxBounces"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(tmp / "all/ablation.png"));
    std::set<std::string> seen;
    std::string parts;
    for (int i = 0; i < 3; ++i) {
        std::string shard = std::to_string(i) + "/3";
        r = runLoom("run " + script("ablation.lua") + " --shard " + shard + common + " out=parts",
                    tmp);
        ASSERT_EQ(r.exitCode, 0) << shard << "\n" << r.err;
        std::string part = "parts/ablation.PART-" + std::to_string(i) + ".csv";
        script::CsvTable table = script::readCsv(tmp / part);
        ASSERT_TRUE(table.sweep.has_value()) << part;
        EXPECT_EQ(table.sweep->index, uint32_t(i));
        EXPECT_EQ(table.sweep->count, 3u);
        for (auto& row : table.rows) EXPECT_TRUE(seen.insert(row[0]).second) << "disjoint";
        parts += " " + part;
    }
    EXPECT_FALSE(fs::exists(tmp / "parts/ablation.csv")) << "a shard writes its part only";
    EXPECT_EQ(seen, (std::set<std::string>{"1", "2", "3", "4", "5"}));
    r = runLoom("merge merged.csv" + parts, tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    std::string all = readFile(tmp / "all/ablation.csv");
    EXPECT_EQ(readFile(tmp / "merged.csv"), all);
    EXPECT_EQ(std::count(all.begin(), all.end(), '\n'), 6);
}

// A Slurm array task takes its shard from SLURM_ARRAY_TASK_ID - _MIN of _COUNT, or of
// LOOM_SWEEP_TASKS with base 0 in a sweep-submit job (a resubmitted subset keeps its shards).
TEST(LoomRun, ShardOfASlurmArrayTask) {
    TempDir tmp("loom-run");
    writeFile(tmp / "s.lua",
              "print(string.format('shard %d/%d', loom.shard.index, loom.shard.count))\n");
    auto r = runLoom("run s.lua", tmp,
                     "SLURM_ARRAY_TASK_ID=5 SLURM_ARRAY_TASK_MIN=4 SLURM_ARRAY_TASK_COUNT=3");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("shard 1/3"), std::string::npos) << r.out;
    r = runLoom("run --shard slurm s.lua", tmp, "SLURM_ARRAY_TASK_ID=5 LOOM_SWEEP_TASKS=8");
    EXPECT_NE(r.out.find("shard 5/8"), std::string::npos) << r.out << r.err;
    r = runLoom("run s.lua --shard 2/4", tmp,
                "SLURM_ARRAY_TASK_ID=0 SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_COUNT=3");
    EXPECT_NE(r.out.find("shard 2/4"), std::string::npos) << "--shard I/N wins: " << r.out;
    r = runLoom("run --shard slurm s.lua", tmp, "env -u SLURM_ARRAY_TASK_ID");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("SLURM_ARRAY_TASK_ID is not set"), std::string::npos) << r.err;
    r = runLoom("run s.lua", tmp,
                "SLURM_ARRAY_TASK_ID=9 SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_COUNT=3");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("task 9 is not in [0, 3)"), std::string::npos) << r.err;
    r = runLoom("run s.lua --phase plot", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("--phase must be run or merge"), std::string::npos) << r.err;
}

TEST(LoomRun, WaterCausticsScript) {
    // The animated pool (its water a heightfield of the frame time) by MNEE with dimension
    // reduction: one PNG per step, and the water moved between them.
    TempDir tmp("loom-run");
    auto r = runLoom("run " + script("water_caustics.lua") +
                         " width=24 height=18 steps=3 dt=4 frames=1 resolution=24 out=wc",
                     tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* f : {"wc/frame_0000.png", "wc/frame_0001.png", "wc/frame_0002.png",
                          "wc/water_caustics.csv", "wc/scene_n24.json"})
        EXPECT_TRUE(fs::exists(tmp / f)) << f;
    EXPECT_NE(r.out.find("scene update ms"), std::string::npos) << r.out;
    ImageData a = readImage(tmp / "wc/frame_0000.png"), b = readImage(tmp / "wc/frame_0002.png");
    EXPECT_GT(computeMetric(Metric::MSE, a, b), 1e-6);
}

TEST(LoomRun, TurntableScript) {
    TempDir tmp("loom-run");
    auto r = runLoom(
        "run " + script("turntable.lua") + " width=16 height=16 views=3 frames=1 out=tt", tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* f :
         {"tt/path.json", "tt/frame_0000.png", "tt/frame_0001.png", "tt/frame_0002.png"})
        EXPECT_TRUE(fs::exists(tmp / f)) << f;
    // The views differ: the camera moved.
    ImageData a = readImage(tmp / "tt/frame_0000.png"), b = readImage(tmp / "tt/frame_0002.png");
    EXPECT_GT(computeMetric(Metric::MSE, a, b), 1e-5);
}

TEST(LoomRun, ReSTIREqualTimeScript) {
    TempDir tmp("loom-run");
    auto r = runLoom("run " + script("restir_equal_time.lua") +
                         " width=16 height=16 budget_ms=20 steps=2 move_frames=3 repeats=1"
                         " ref_frames=1 ref_spp=4 scenes=scenes/cornell_box.json,no/such.json"
                         " out=rt",
                     tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* s : {"skipping no/such.json", "ReSTIR PT", "static", "still", "moving",
                          "relMSE", "GPU ms per pass", "spatial"})
        EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
    script::CsvTable csv = script::readCsv(tmp / "rt/restir_equal_time.csv");
    EXPECT_EQ(csv.header, (std::vector<std::string>{
                              "index", "scene", "camera", "config", "budget_ms", "gpu_ms", "frames",
                              "spp", "relmse", "relmse_trim", "mse", "mape", "flip"}));
    // Static: 2 configurations x 2 budget steps; still and moving: one row per configuration.
    ASSERT_EQ(csv.rows.size(), 8u);
    int moving = 0, still = 0;
    for (auto& row : csv.rows) {
        EXPECT_EQ(row[1], "cornell_box");
        EXPECT_GT(std::stod(row[8]), 0.0) << "relMSE";
        EXPECT_GT(std::stod(row[10]), 0.0) << "MSE";
        if (row[2] == "static") {
            EXPECT_GE(std::stod(row[5]), std::stod(row[4])) << "budget met";
        } else {
            ++(row[2] == "still" ? still : moving);
            EXPECT_EQ(row[6], "3") << "frames of the camera swing";
            EXPECT_GE(std::stoi(row[7]), 1) << "spp";
            double flip = std::stod(row[12]);
            EXPECT_GT(flip, 0.0) << "FLIP";
            EXPECT_LT(flip, 1.0) << "FLIP";
        }
    }
    EXPECT_EQ(moving, 2);
    EXPECT_EQ(still, 2);
    for (const char* f :
         {"rt/summary.csv", "rt/cornell_box_static.png", "rt/cornell_box_PT_still.png",
          "rt/cornell_box_static.svg", "rt/cornell_box_path.json",
          "rt/cornell_box_ReSTIR_PT_static.png", "rt/cornell_box_PT_moving.png"})
        EXPECT_TRUE(fs::exists(tmp / f)) << f;
}

TEST(LoomRun, TailDiagnosticsScript) {
    // Per-frame tail statistics of psms's caustic: one CSV row per report, running counts that
    // add up, and a pass parameter given as PASS.PARAM=VALUE reaching the renderer.
    TempDir tmp("loom-run");
    auto r = runLoom("run " + script("tail_diagnostics.lua") +
                         " size=8 frames=6 every=3 region=0,0,4,8 psms.maxTrials=64 "
                         "psms.prior=false out=td",
                     tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("top 1%"), std::string::npos) << r.out;
    script::CsvTable csv = script::readCsv(tmp / "td/tail.csv");
    ASSERT_GE(csv.header.size(), 7u);
    EXPECT_EQ(csv.header[0], "frames");
    EXPECT_EQ(csv.header[6], "top1_share");
    ASSERT_EQ(csv.rows.size(), 2u);
    EXPECT_EQ(csv.rows[0][0], "3");
    EXPECT_EQ(csv.rows[1][0], "6");
    for (auto& row : csv.rows) {
        EXPECT_GE(std::stod(row[1]), 0.0) << "mean";
        double nz = std::stod(row[3]), share = std::stod(row[6]);
        EXPECT_GE(nz, 0.0);
        EXPECT_LE(nz, 1.0);
        EXPECT_GE(share, 0.0);
        EXPECT_LE(share, 1.0);
    }
    EXPECT_NE(r.out.find("region 0,0 4x8"), std::string::npos) << r.out;
    r = runLoom("run " + script("tail_diagnostics.lua") + " size=8 frames=1 psms.noSuch=1", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("noSuch"), std::string::npos) << r.err;
    r = runLoom("run " + script("tail_diagnostics.lua") + " size=8 frames=1 region=4,0,8,8", tmp);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("region: x,y,w,h inside the 8x8 image"), std::string::npos) << r.err;
}

TEST(LoomRun, SmsEqualTimeScript) {
    TempDir tmp("loom-run");
    auto r = runLoom("run " + script("sms_equal_time.lua") +
                         " width=16 height=16 budget_ms=50 steps=2 ref_frames=1 ref_spp=4"
                         " mask_frames=1 regions=2 scenes=scenes/curved_mirror.json,no/such.json"
                         " out=se",
                     tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* s : {"skipping no/such.json", "caustic region", "SMS unbiased", "MNEE",
                          "relMSE caustic", "RMSE caustic", "ratio vs PT", "energy caustic"})
        EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
    script::CsvTable csv = script::readCsv(tmp / "se/sms_equal_time.csv");
    EXPECT_EQ(csv.header, (std::vector<std::string>{"scene", "config", "budget_ms", "gpu_ms",
                                                    "frames", "index", "energy_caustic", "relmse",
                                                    "relmse_caustic", "rmse_caustic"}));
    ASSERT_EQ(csv.rows.size(), 12u);  // 6 configurations x 2 budget steps
    for (auto& row : csv.rows) EXPECT_GE(std::stod(row[3]), std::stod(row[2])) << "budget met";
    EXPECT_EQ(script::readCsv(tmp / "se/sms_regions.csv").rows.size(), 24u);  // 6 x 2 x 2
    for (const char* f : {"se/curved_mirror_mask.png", "se/curved_mirror_caustic_relmse.svg"})
        EXPECT_TRUE(fs::exists(tmp / f)) << f;
}

// The reconstruction error split into its primal and gradient parts, for both gradient graphs.
TEST(LoomRun, GradientErrorSplitScript) {
    TempDir tmp("loom-run");
    auto r = runLoom("run " + script("gradient_error_split.lua") +
                         " scene=scenes/cornell_box.json width=16 height=16 repeats=1 move_frames=3"
                         " ref_frames=1 ref_spp=4 direct_frames=2 out=gs",
                     tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* s : {"solve of the exact inputs", "ReSTIR G-PT", "gradient after ReSTIR",
                          "exact gradients", "exact primal", "non-integrable"})
        EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
    script::CsvTable csv = script::readCsv(tmp / "gs/gradient_error_split.csv");
    ASSERT_EQ(csv.rows.size(), 2u);
    ASSERT_EQ(csv.header[0], "scene");
    for (auto& row : csv.rows)
        for (size_t c = 2; c < row.size(); ++c) EXPECT_GE(std::stod(row[c]), 0.0) << csv.header[c];
    EXPECT_TRUE(fs::exists(tmp / "gs/cornell_box_ReSTIR_G_PT_gradient_error.png"));
}

// The committed normal map of scenes/normal_mapped_water.json is what its generator writes.
TEST(LoomRun, RippleNormalMapScriptWritesTheCommittedMap) {
    TempDir tmp("loom-run");
    auto r = runLoom("run " + script("make_ripple_normal_map.lua") + " out=ripples.exr", tmp);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    ImageData made = readImage(tmp / "ripples.exr");
    ImageData committed = readImage(fs::path(kSource) / "scenes/textures/ripples_normal.exr");
    ASSERT_EQ(made.width, committed.width);
    ASSERT_EQ(made.height, committed.height);
    ASSERT_EQ(made.pixels.size(), committed.pixels.size());
    double worst = 0;
    for (size_t i = 0; i < made.pixels.size(); ++i)
        worst = std::max(worst, double(std::abs(made.pixels[i] - committed.pixels[i])));
    EXPECT_LT(worst, 1e-3) << "rerun scripts/make_ripple_normal_map.lua and commit the map";
}

}  // namespace
