// JSON round trip of graphs (parameters included) and the loom CLI's validate/passes commands
// and exit codes. No GPU: `loom validate` and `loom passes` never create a device.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/graph/RenderGraph.h"
#include "tests/support/TestSupport.h"

namespace {

namespace fs = std::filesystem;
using loom::json;
using loom::PassRegistry;
using loom::RenderGraph;
using loom::test::TempDir;

std::vector<std::string> graphFiles() {
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(std::string(LOOM_SOURCE_DIR) + "/graphs"))
        if (e.path().extension() == ".json") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    return files;
}

// A graph exercising every ComputePass constant type with non-default values, defines, a
// dispatch size, a persistent resource, a buffer output and an execution-only edge.
const char* kConstantsGraph = R"({
  "name": "constants",
  "description": "round-trip fixture",
  "passes": [
    {"name": "gen", "type": "ComputePass", "params": {
      "shader": "gen.comp",
      "outputs": {"color": {"glsl": "colorImage"},
                  "preview": {"format": "rgba16f", "scale": 0.5},
                  "counts": {"kind": "buffer", "bytesPerPixel": 4, "optional": true}},
      "persistent": {"history": {"format": "rg32f"}},
      "constants": {
        "gain": {"type": "float", "default": 1.0, "min": 0, "doc": "scale"},
        "radius": {"type": "int", "default": 2, "min": 0, "max": 8},
        "samples": {"type": "uint", "default": 4},
        "flip": {"type": "bool", "default": false},
        "offset": {"type": "vec2", "default": [0, 0]},
        "tint": {"type": "vec3", "default": [1, 1, 1]},
        "plane": {"type": "vec4"}
      },
      "defines": {"USE_FAST_PATH": 1, "MODE": "linear"},
      "dispatch": [16, 8],
      "gain": 2.75, "radius": 5, "samples": 7, "flip": true, "offset": [0.25, -1.5],
      "tint": [0.1, 0.2, 0.3], "plane": [1, 2, 3, 4]}},
    {"name": "acc", "type": "Accumulate", "params": {"maxFrames": 12}},
    {"name": "tm", "type": "ToneMap", "params": {"exposure": -1.5, "operator": "reinhard",
                                                 "srgb": false}}
  ],
  "edges": [["gen.color", "acc.input"], ["acc.output", "tm.input"], ["gen", "tm"]],
  "outputs": ["tm.output"]
})";

TEST(GraphJson, RoundTripEveryCommittedGraph) {
    auto files = graphFiles();
    ASSERT_FALSE(files.empty());
    TempDir tmp("loom-roundtrip");
    for (const auto& f : files) {
        SCOPED_TRACE(f);
        auto a = RenderGraph::load(f);
        // Through toJson text, parsed as the same file so relative paths resolve alike.
        auto b = RenderGraph::parse(a->toJson().dump(2), f);
        EXPECT_TRUE(a->equals(*b));
        EXPECT_EQ(a->toJson(), b->toJson());
        // Through save(): the saved text reloads to an equal graph.
        std::string saved = tmp / fs::path(f).filename().string();
        a->save(saved);
        auto c = RenderGraph::parse(loom::test::readFile(saved), f);
        EXPECT_TRUE(a->equals(*c));
        // Everything the file states survives, parameters included.
        json original = json::parse(loom::test::readFile(f));
        json round = c->toJson();
        if (original.contains("description")) {
            EXPECT_EQ(round.value("description", ""), original["description"]);
        }
        EXPECT_EQ(round["outputs"], original["outputs"]);
        EXPECT_EQ(round["edges"], original.value("edges", json::array()));
        for (size_t i = 0; i < original["passes"].size(); ++i) {
            const json& p = original["passes"][i];
            EXPECT_EQ(round["passes"][i]["name"], p["name"]);
            EXPECT_EQ(round["passes"][i]["type"], p["type"]);
            const json params = p.value("params", json::object());
            for (auto& [k, v] : params.items())
                EXPECT_EQ(c->getParam(p["name"].get<std::string>() + "." + k), v)
                    << p["name"] << "." << k;
        }
    }
}

TEST(GraphJson, RoundTripComputePassConstants) {
    auto a = RenderGraph::parse(kConstantsGraph, "constants.json");
    EXPECT_EQ(a->getParam("gen.gain"), 2.75);
    EXPECT_EQ(a->getParam("gen.radius"), 5);
    EXPECT_EQ(a->getParam("gen.samples"), 7);
    EXPECT_EQ(a->getParam("gen.flip"), true);
    EXPECT_EQ(a->getParam("gen.offset"), json({0.25, -1.5}));
    EXPECT_EQ(a->getParam("gen.tint"), json({0.1, 0.2, 0.3}));
    EXPECT_EQ(a->getParam("gen.plane"), json({1.0, 2.0, 3.0, 4.0}));

    TempDir tmp("loom-roundtrip");
    a->save(tmp / "constants.json");
    auto b = RenderGraph::load(tmp / "constants.json");
    EXPECT_TRUE(a->equals(*b));
    EXPECT_EQ(b->name(), "constants");
    EXPECT_EQ(b->toJson().value("description", ""), "round-trip fixture");
    for (const char* p : {"gen.gain", "gen.radius", "gen.samples", "gen.flip", "gen.offset",
                          "gen.tint", "gen.plane", "gen.defines", "gen.dispatch", "acc.maxFrames",
                          "tm.exposure", "tm.operator", "tm.srgb"})
        EXPECT_EQ(a->getParam(p), b->getParam(p)) << p;
    ASSERT_EQ(b->edges().size(), 3u);
    EXPECT_FALSE(b->edges()[0].isExecutionOnly());
    EXPECT_TRUE(b->edges()[2].isExecutionOnly());
    // The declared ports come back too (they live in the parameters).
    auto cg = b->compile(32, 16);
    EXPECT_EQ(cg.resources[cg.portResource.at("gen.preview")].format, loom::gpu::Format::RGBA16F);
    EXPECT_EQ(cg.resources[cg.portResource.at("gen.preview")].width, 16u);
    EXPECT_EQ(cg.portResource.count("gen.counts"), 0u);  // optional and unused
    EXPECT_EQ(cg.resources[cg.portResource.at("gen#history")].format, loom::gpu::Format::RG32F);

    // equals() sees a change in any parameter, edge or output.
    b->setParam("gen.tint", json({0.1, 0.2, 0.31}));
    EXPECT_FALSE(a->equals(*b));
    b->setParam("gen.tint", json({0.1, 0.2, 0.3}));
    EXPECT_TRUE(a->equals(*b));
    b->disconnect("gen", "tm");
    EXPECT_FALSE(a->equals(*b));
    b->connect("gen", "tm");
    EXPECT_TRUE(a->equals(*b));
    b->markOutput("acc.output");
    EXPECT_FALSE(a->equals(*b));
}

TEST(GraphJson, RemovedConstantDropsItsValue) {
    auto g = RenderGraph::parse(kConstantsGraph, "constants.json");
    json constants = g->getParam("gen.constants");
    constants.erase("gain");
    g->setParam("gen.constants", constants);
    EXPECT_THROW(g->getParam("gen.gain"), loom::UserError);
    EXPECT_FALSE(g->toJson()["passes"][0]["params"].contains("gain"));
    auto back = RenderGraph::parse(g->toJson().dump(), "constants.json");
    EXPECT_TRUE(g->equals(*back));
}

// ---------------------------------------------------------------------------------------------
// CLI

struct CommandResult {
    int exitCode = -1;
    std::string out, err;
};

CommandResult runLoom(const std::string& args) {
    TempDir tmp("loom-cli");
    std::string cmd = std::string("'") + LOOM_BINARY + "' " + args + " >'" + (tmp / "out") +
                      "' 2>'" + (tmp / "err") + "'";
    int status = std::system(cmd.c_str());
    CommandResult r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = loom::test::readFile(tmp / "out");
    r.err = loom::test::readFile(tmp / "err");
    return r;
}

// One `loom validate` over every graph (it compiles each graph's kernels, seconds per graph on
// lavapipe): one "OK <file>" line per graph, in order, and nothing on stderr.
TEST(LoomCli, ValidateEveryCommittedGraph) {
    const auto files = graphFiles();
    std::string all;
    for (const auto& f : files) all += " '" + f + "'";
    auto r = runLoom("validate" + all);
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    std::istringstream lines(r.out);
    std::string line;
    for (const auto& f : files) {
        ASSERT_TRUE(bool(std::getline(lines, line))) << "no line for " << f << "\n" << r.out;
        EXPECT_EQ(line.rfind("OK " + f + " (", 0), 0u) << line;
    }
    EXPECT_FALSE(bool(std::getline(lines, line))) << "an extra line: " << line;
}

TEST(LoomCli, PassesJsonCoversEveryRegisteredPass) {
    auto r = runLoom("passes --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    json all = json::parse(r.out);
    ASSERT_TRUE(all.is_array());
    std::vector<std::string> listed;
    for (const auto& p : all) listed.push_back(p["type"]);
    EXPECT_EQ(listed, PassRegistry::instance().types());
    for (const auto& p : all) {
        SCOPED_TRACE(p["type"].get<std::string>());
        auto pass = PassRegistry::instance().create(p["type"], "p");
        auto refl = pass->reflection();
        std::vector<std::string> params, expectedParams;
        for (auto& x : p["params"]) params.push_back(x["name"]);
        for (auto& x : refl.params()) expectedParams.push_back(x.name);
        EXPECT_EQ(params, expectedParams);
        for (auto& x : p["params"])
            EXPECT_EQ(x["default"], refl.findParam(x["name"])->defaultValue) << x["name"];
        size_t ports = p["inputs"].size() + p["outputs"].size();
        EXPECT_EQ(ports, refl.ports().size());
        for (auto& x : p["inputs"]) {
            auto* d = refl.findPort(x["name"]);
            ASSERT_TRUE(d && d->isInput) << x["name"];
        }
        for (auto& x : p["outputs"]) {
            auto* d = refl.findPort(x["name"]);
            ASSERT_TRUE(d && !d->isInput) << x["name"];
        }
        EXPECT_EQ(p["persistent"].size(), refl.persistent().size());
        EXPECT_FALSE(p["doc"].get<std::string>().empty());
    }
    // Spot-check one declaration end to end.
    auto tm = std::find_if(all.begin(), all.end(), [](auto& p) { return p["type"] == "ToneMap"; });
    ASSERT_NE(tm, all.end());
    json exposure = (*tm)["params"][0];
    EXPECT_EQ(exposure["name"], "exposure");
    EXPECT_EQ(exposure["type"], "float");
    EXPECT_EQ(exposure["min"], -20.0);
    EXPECT_EQ(exposure["max"], 20.0);
    EXPECT_EQ((*tm)["params"][1]["choices"], json({"clamp", "reinhard", "aces"}));
    EXPECT_EQ((*tm)["inputs"][0]["format"], "rgba32f");
}

// --out with an HDR extension writes linear radiance (graphs/pt.json marks tm.output first),
// and says so; a graph with only tone-mapped outputs is refused for .exr with a clear message.
TEST(LoomCli, OutHdrWritesTheFirstLinearOutput) {
    TempDir tmp("loom-out-hdr");
    std::string graph = std::string(LOOM_SOURCE_DIR) + "/graphs/pt.json";
    std::string scene = std::string(LOOM_SOURCE_DIR) + "/scenes/cornell_box.json";
    const char* oldLog = std::getenv("LOOM_LOG");
    std::string savedLog = oldLog ? oldLog : "";
    ::setenv("LOOM_LOG", "info", 1);  // ctest runs tests at "warning"; the choice is an info line
    auto r = runLoom("render '" + graph + "' --scene '" + scene + "' --width 8 --height 8 --out '" +
                     (tmp / "a.exr") + "'");
    if (oldLog)
        ::setenv("LOOM_LOG", savedLog.c_str(), 1);
    else
        ::unsetenv("LOOM_LOG");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("(accum.output,"), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("writing the linear output accum.output"), std::string::npos) << r.err;
    r = runLoom("render '" + graph + "' --scene '" + scene + "' --width 8 --height 8 --out '" +
                (tmp / "a.png") + "'");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("(tm.output,"), std::string::npos) << r.out;
    loom::test::writeFile(tmp / "tm_only.json", R"({"name": "tm_only", "passes": [
        {"name": "pt", "type": "PathTracer"}, {"name": "tm", "type": "ToneMap"}],
        "edges": [["pt.color", "tm.input"]], "outputs": ["tm.output"]})");
    r = runLoom("render '" + (tmp / "tm_only.json") + "' --scene '" + scene +
                "' --width 8 --height 8 --out '" + (tmp / "b.exr") + "'");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("tone-mapped (tm.output)"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(tmp / "b.exr"));
}

TEST(LoomCli, UsageErrorsExitTwo) {
    auto none = runLoom("");
    EXPECT_EQ(none.exitCode, 2);
    EXPECT_NE(none.out.find("usage: loom <command>"), std::string::npos);

    auto unknown = runLoom("frobnicate");
    EXPECT_EQ(unknown.exitCode, 2);
    // The command list grows with the CLI; the message names the culprit and lists them.
    EXPECT_EQ(unknown.err.rfind("error: unknown command 'frobnicate' (commands: render, validate, "
                                "passes, devices",
                                0),
              0u)
        << unknown.err;
    EXPECT_EQ(std::count(unknown.err.begin(), unknown.err.end(), '\n'), 1);

    auto noGraph = runLoom("render");
    EXPECT_EQ(noGraph.exitCode, 2);
    EXPECT_EQ(noGraph.err, "error: render: missing GRAPH (see loom render --help)\n");

    std::string graph = std::string(LOOM_SOURCE_DIR) + "/graphs/hello_compute.json";
    auto badWidth = runLoom("render '" + graph + "' --width abc");
    EXPECT_EQ(badWidth.exitCode, 2);
    EXPECT_EQ(badWidth.err, "error: --width expects a non-negative integer, got 'abc'\n");

    auto badOption = runLoom("validate --strict");
    EXPECT_EQ(badOption.exitCode, 2);
    EXPECT_EQ(badOption.err, "error: validate: unknown option '--strict'\n");

    auto help = runLoom("render --help");
    EXPECT_EQ(help.exitCode, 0);
    EXPECT_NE(help.out.find("usage: loom render GRAPH"), std::string::npos);
}

TEST(LoomCli, BadGraphExitsTwoWithMessageOnStderr) {
    TempDir tmp("loom-cli");
    std::string bad = tmp / "bad.json";
    const std::string badText = R"({
  "passes": [{"name": "tm", "type": "ToneMap", "params": {"exposure": 50}}],
  "outputs": ["tm.output"]
})";
    loom::test::writeFile(bad, badText);
    std::string good = std::string(LOOM_SOURCE_DIR) + "/graphs/hello_compute.json";
    const std::string expected =
        "error: " + loom::test::locationOf(bad, badText, "\"exposure\"") +
        ": pass 'tm' (ToneMap): parameter 'exposure' = 50 is out of range [-20, 20]\n";

    auto v = runLoom("validate '" + good + "' '" + bad + "'");
    EXPECT_EQ(v.exitCode, 2);
    EXPECT_EQ(v.err, expected);
    EXPECT_EQ(v.out.rfind("OK " + good, 0), 0u) << v.out;  // the good file is still checked

    // render reports the same error before it starts a device.
    auto r = runLoom("render '" + bad + "'");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_EQ(r.err, expected);

    // Errors found only by compiling (an unconnected required input) also exit 2.
    std::string unconnected = tmp / "unconnected.json";
    loom::test::writeFile(
        unconnected,
        R"({"passes": [{"name": "tm", "type": "ToneMap"}], "outputs": ["tm.output"]})");
    auto u = runLoom("validate '" + unconnected + "'");
    EXPECT_EQ(u.exitCode, 2);
    EXPECT_EQ(u.err, "error: " + unconnected +
                         ":1:13: pass 'tm' (ToneMap): required input 'input' is not connected\n");

    auto missing = runLoom("validate '" + (tmp / "nope.json") + "'");
    EXPECT_EQ(missing.exitCode, 2);
    EXPECT_EQ(missing.err, "error: " + (tmp / "nope.json") + ": cannot open graph file\n");
}

}  // namespace
