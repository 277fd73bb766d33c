// Graph validation without a GPU: every class of bad input gets a GraphError whose message
// names the culprit (pass, port, parameter, field) and the file:line:col it came from.
#include <gtest/gtest.h>

#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/graph/RenderGraph.h"
#include "core/image/Image.h"
#include "tests/support/TestSupport.h"

namespace {

using loom::GraphError;
using loom::PassRegistry;
using loom::RenderGraph;
using loom::test::locationOf;

constexpr const char* kFile = "graphs/bad.json";

// Parses `text` and returns the GraphError's message; fails the test when nothing is thrown.
std::string parseError(const std::string& text) {
    try {
        RenderGraph::parse(text, kFile);
    } catch (const GraphError& e) {
        return e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected GraphError, got another exception: " << e.what();
        return e.what();
    }
    ADD_FAILURE() << "graph was accepted:\n" << text;
    return "";
}

// Parses (must succeed) and compiles (must fail); returns the compile error.
std::string compileError(const std::string& text) {
    auto g = RenderGraph::parse(text, kFile);
    try {
        g->compile(16, 16);
    } catch (const GraphError& e) {
        return e.what();
    }
    ADD_FAILURE() << "graph compiled:\n" << text;
    return "";
}

// The message must start with the location, then name everything in `parts`.
void expectMessage(const std::string& msg, const std::string& where,
                   const std::vector<std::string>& parts) {
    EXPECT_EQ(msg.rfind(where + ": ", 0), 0u)
        << "message does not start with " << where << ":\n  " << msg;
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << p << "\n  in: " << msg;
}

std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

// A minimal ComputePass declaration with one rgba32f input "in" and one output "out".
std::string relay(const std::string& name) {
    return R"({"name": ")" + name + R"(", "type": "ComputePass", "params": {"shader": "x.comp",
       "inputs": {"in": {"format": "rgba32f", "optional": true}},
       "outputs": {"out": {"format": "rgba32f"}}}})";
}

TEST(GraphValidation, MalformedJsonNamesLineAndColumn) {
    const std::string text =
        "{\n"
        "  \"name\": \"bad\",\n"
        "  \"passes\": [\n"
        "    {\"name\": \"tm\" \"type\": \"ToneMap\"}\n"
        "  ]\n"
        "}\n";
    std::string msg;
    try {
        RenderGraph::parse(text, kFile);
        ADD_FAILURE() << "malformed JSON accepted";
    } catch (const loom::UserError& e) {
        msg = e.what();
    }
    // The parser stops at the end of the unexpected token "type" (line 4, column 24).
    expectMessage(msg, std::string(kFile) + ":4:24", {"JSON syntax error", "unexpected string"});
}

TEST(GraphValidation, MalformedJsonTrailingCommaOnNextLine) {
    const std::string text = "{\"passes\": [\n  1,\n]\n}";
    std::string msg;
    try {
        RenderGraph::parse(text, kFile);
    } catch (const loom::UserError& e) {
        msg = e.what();
    }
    expectMessage(msg, std::string(kFile) + ":3:1", {"JSON syntax error"});
}

TEST(GraphValidation, UnknownPassTypeListsKnownTypes) {
    const std::string text = R"({
  "passes": [
    {"name": "tm", "type": "ToneMapper"}
  ],
  "outputs": ["tm.output"]
})";
    std::string msg = parseError(text);
    expectMessage(msg, locationOf(kFile, text, "\"type\""),
                  {"pass 'tm'", "unknown pass type 'ToneMapper'",
                   "known types: " + join(PassRegistry::instance().types())});
}

TEST(GraphValidation, UnknownParameterListsValidOnes) {
    const std::string text = R"({
  "passes": [
    {"name": "src", "type": "ImageLoader"},
    {"name": "tm", "type": "ToneMap", "params": {"operator": "clamp", "expsure": 1.0}}
  ],
  "edges": [["src.output", "tm.input"]],
  "outputs": ["tm.output"]
})";
    std::string msg = parseError(text);
    expectMessage(msg, locationOf(kFile, text, "\"expsure\""),
                  {"'tm'", "no parameter 'expsure'", "valid parameters: exposure, operator, srgb"});
}

TEST(GraphValidation, WrongParameterType) {
    const std::string text = R"({
  "passes": [
    {"name": "tm", "type": "ToneMap",
     "params": {"exposure": "bright"}}
  ],
  "outputs": ["tm.output"]
})";
    std::string msg = parseError(text);
    expectMessage(msg, locationOf(kFile, text, "\"exposure\""),
                  {"pass 'tm' (ToneMap)", "parameter 'exposure' expects a number",
                   "got \"bright\" (string)"});
}

TEST(GraphValidation, WrongParameterTypeBoolAndInt) {
    const std::string boolText = R"({"passes": [{"name": "tm", "type": "ToneMap",
  "params": {"srgb": 1}}], "outputs": ["tm.output"]})";
    expectMessage(parseError(boolText), locationOf(kFile, boolText, "\"srgb\""),
                  {"parameter 'srgb' expects a bool", "got 1 (number)"});
    const std::string intText = R"({"passes": [{"name": "acc", "type": "Accumulate",
  "params": {"maxFrames": 2.5}}], "outputs": ["acc.output"]})";
    expectMessage(parseError(intText), locationOf(kFile, intText, "\"maxFrames\""),
                  {"pass 'acc' (Accumulate)", "parameter 'maxFrames' expects an integer"});
}

TEST(GraphValidation, ParameterOutOfRange) {
    const std::string text = R"({
  "passes": [
    {"name": "tm", "type": "ToneMap", "params": {
      "exposure": 25}}
  ],
  "outputs": ["tm.output"]
})";
    std::string msg = parseError(text);
    expectMessage(msg, locationOf(kFile, text, "\"exposure\""),
                  {"pass 'tm' (ToneMap)", "parameter 'exposure' = 25 is out of range [-20, 20]"});
    const std::string below = R"({"passes": [{"name": "acc", "type": "Accumulate",
      "params": {"maxFrames": -1}}], "outputs": ["acc.output"]})";
    expectMessage(parseError(below), locationOf(kFile, below, "\"maxFrames\""),
                  {"parameter 'maxFrames' = -1 is out of range [0, inf]"});
}

TEST(GraphValidation, UnknownEnumChoice) {
    const std::string text = R"({
  "passes": [{"name": "tm", "type": "ToneMap", "params": {"operator": "filmic"}}],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "\"operator\""),
                  {"pass 'tm' (ToneMap)",
                   "parameter 'operator' = \"filmic\" is not one of: "
                   "clamp, reinhard, aces"});
}

TEST(GraphValidation, EdgeToMissingNode) {
    const std::string text = R"({
  "passes": [
    {"name": "src", "type": "ImageLoader"},
    {"name": "tm", "type": "ToneMap"}
  ],
  "edges": [
    ["src.output", "tm.input"],
    ["ghost.output", "tm.input"]
  ],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "[\"ghost"),
                  {"unknown pass 'ghost'", "passes: src, tm"});
}

TEST(GraphValidation, EdgeToMissingPortListsPorts) {
    const std::string text = R"({
  "passes": [
    {"name": "src", "type": "ImageLoader"},
    {"name": "tm", "type": "ToneMap"}
  ],
  "edges": [["src.output", "tm.color"]],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "[\"src.output\""),
                  {"pass 'tm' (ToneMap) has no input 'color'", "inputs: input"});
    const std::string outText = R"({
  "passes": [
    {"name": "src", "type": "ImageLoader"},
    {"name": "tm", "type": "ToneMap"}
  ],
  "edges": [["src.image", "tm.input"]],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(outText), locationOf(kFile, outText, "[\"src.image\""),
                  {"pass 'src' (ImageLoader) has no output 'image'", "outputs: output"});
}

TEST(GraphValidation, TextureBufferKindMismatch) {
    const std::string text = R"({
  "passes": [
    {"name": "em", "type": "ErrorMetric"},
    {"name": "tm", "type": "ToneMap"}
  ],
  "edges": [["em.value", "tm.input"]],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "[\"em.value\""),
                  {"em.value is a buffer but tm.input expects a texture"});
}

TEST(GraphValidation, FormatMismatch) {
    const std::string text = R"({
  "passes": [
    {"name": "mask", "type": "ComputePass", "params": {
      "shader": "mask.comp", "outputs": {"alpha": {"format": "r32f"}}}},
    {"name": "tm", "type": "ToneMap"}
  ],
  "edges": [
    ["mask.alpha", "tm.input"]
  ],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "[\"mask.alpha\""),
                  {"format mismatch", "mask.alpha is r32f", "tm.input expects rgba32f"});
}

TEST(GraphValidation, TwoEdgesIntoOneInput) {
    const std::string text = R"({
  "passes": [
    {"name": "a", "type": "ImageLoader"},
    {"name": "b", "type": "ImageLoader"},
    {"name": "tm", "type": "ToneMap"}
  ],
  "edges": [
    ["a.output", "tm.input"],
    ["b.output", "tm.input"]
  ],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "[\"b.output\""),
                  {"input tm.input already has an edge from a.output"});
}

// Extracts the pass names after "cycle: " ("x -> y -> x").
std::vector<std::string> cycleNodes(const std::string& msg) {
    auto pos = msg.find("cycle: ");
    if (pos == std::string::npos) return {};
    std::vector<std::string> nodes;
    std::stringstream ss(msg.substr(pos + 7));
    std::string tok;
    while (ss >> tok)
        if (tok != "->") nodes.push_back(tok);
    return nodes;
}

TEST(GraphValidation, CycleNamesItsNodes) {
    // a and out hang off the cycle x -> y -> z -> x; only x, y, z lie on it. "a" sorts first,
    // so a search that starts at a node downstream of the cycle must still find the cycle.
    const std::string text = R"({
  "passes": [
    )" + relay("a") + R"(,
    )" + relay("x") + R"(,
    )" + relay("y") + R"(,
    )" + relay("z") + R"(,
    )" + relay("out") + R"(
  ],
  "edges": [["x.out", "y.in"], ["y.out", "z.in"], ["z.out", "x.in"], ["y.out", "a.in"],
            ["x.out", "out.in"]],
  "outputs": ["out.out"]
})";
    std::string msg = parseError(text);
    std::vector<std::string> nodes = cycleNodes(msg);
    ASSERT_EQ(nodes.size(), 4u) << msg;
    EXPECT_EQ(nodes.front(), nodes.back()) << msg;
    EXPECT_EQ(std::set<std::string>(nodes.begin(), nodes.end()),
              (std::set<std::string>{"x", "y", "z"}))
        << msg;
    // Each step of the reported cycle is an edge of the graph.
    std::set<std::pair<std::string, std::string>> edges{{"x", "y"}, {"y", "z"}, {"z", "x"}};
    for (size_t i = 0; i + 1 < nodes.size(); ++i)
        EXPECT_TRUE(edges.count({nodes[i], nodes[i + 1]})) << nodes[i] << " -> " << nodes[i + 1];
    // Located at the first named pass's declaration.
    expectMessage(msg, locationOf(kFile, text, "{\"name\": \"" + nodes.front() + "\""),
                  {"graph has a cycle"});
}

TEST(GraphValidation, CycleThroughExecutionOnlyEdge) {
    const std::string text = R"({
  "passes": [
    )" + relay("p") + R"(,
    )" + relay("q") + R"(
  ],
  "edges": [["p.out", "q.in"], ["q", "p"]],
  "outputs": ["q.out"]
})";
    std::string msg = parseError(text);
    std::vector<std::string> nodes = cycleNodes(msg);
    ASSERT_EQ(nodes.size(), 3u) << msg;
    EXPECT_EQ(std::set<std::string>(nodes.begin(), nodes.end()), (std::set<std::string>{"p", "q"}));
}

TEST(GraphValidation, SelfEdge) {
    const std::string text = R"({
  "passes": [)" + relay("p") +
                             R"(],
  "edges": [["p.out", "p.in"]],
  "outputs": ["p.out"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "[\"p.out\", \"p.in\"]"),
                  {"pass 'p' is connected to itself"});
}

TEST(GraphValidation, RequiredInputUnconnected) {
    const std::string text = R"({
  "passes": [
    {"name": "src", "type": "ImageLoader"},
    {"name": "tm", "type": "ToneMap"},
    {"name": "acc", "type": "Accumulate"}
  ],
  "edges": [["src.output", "tm.input"]],
  "outputs": ["tm.output", "acc.output"]
})";
    expectMessage(compileError(text), locationOf(kFile, text, "{\"name\": \"acc\""),
                  {"pass 'acc' (Accumulate): required input 'input' is not connected"});
}

TEST(GraphValidation, NoMarkedOutput) {
    const std::string missing = R"({
  "passes": [{"name": "src", "type": "ImageLoader"}]
})";
    expectMessage(parseError(missing), std::string(kFile) + ":1:1", {"graph has no marked output"});
    const std::string empty = R"({
  "passes": [{"name": "src", "type": "ImageLoader"}],
  "outputs": []
})";
    expectMessage(parseError(empty), locationOf(kFile, empty, "\"outputs\""),
                  {"graph has no marked output"});
}

TEST(GraphValidation, OutputNamesUnknownPassOrPort) {
    const std::string pass = R"({
  "passes": [{"name": "src", "type": "ImageLoader"}],
  "outputs": ["src.output", "tm.output"]
})";
    expectMessage(parseError(pass), locationOf(kFile, pass, "\"tm.output\""),
                  {"output 'tm.output' names unknown pass 'tm'", "passes: src"});
    const std::string port = R"({
  "passes": [{"name": "tm", "type": "ToneMap"}],
  "outputs": ["tm.input"]
})";
    expectMessage(parseError(port), locationOf(kFile, port, "\"tm.input\""),
                  {"pass 'tm' has no output port 'input'", "outputs: output"});
}

TEST(GraphValidation, DuplicatePassName) {
    const std::string text = R"({
  "passes": [
    {"name": "tm", "type": "ToneMap"},
    {"name": "tm", "type": "ToneMap"}
  ],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "\"name\"", 1),
                  {"duplicate pass name 'tm'"});
}

TEST(GraphValidation, UnknownTopLevelField) {
    const std::string text = R"({
  "passes": [{"name": "tm", "type": "ToneMap"}],
  "output": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "\"output\""),
                  {"unknown graph field 'output'",
                   "valid fields: name, description, passes, edges, outputs"});
}

TEST(GraphValidation, UnknownPassField) {
    const std::string text = R"({
  "passes": [{"name": "tm", "type": "ToneMap", "param": {"exposure": 1}}],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "\"param\""),
                  {"unknown pass field 'param'", "valid fields: name, type, params"});
}

TEST(GraphValidation, ComputePassDeclarationErrors) {
    const std::string format = R"({
  "passes": [{"name": "k", "type": "ComputePass", "params": {"shader": "k.comp",
    "outputs": {"color": {"format": "rgb32f"}}}}],
  "outputs": ["k.color"]
})";
    expectMessage(parseError(format), locationOf(kFile, format, "\"outputs\""),
                  {"pass 'k' (ComputePass)", "output 'color': unknown format 'rgb32f'"});
    const std::string constant = R"({
  "passes": [{"name": "k", "type": "ComputePass", "params": {"shader": "k.comp",
    "outputs": {"color": {}}, "constants": {"radius": {"type": "int", "default": 1, "min": 0}},
    "radius": -3}}],
  "outputs": ["k.color"]
})";
    expectMessage(parseError(constant), locationOf(kFile, constant, "\"radius\"", 1),
                  {"pass 'k' (ComputePass)", "parameter 'radius' = -3 is out of range"});
}

TEST(GraphValidation, RejectedComputePassEditKeepsItsPorts) {
    const std::string text = R"({
  "passes": [)" + relay("k") +
                             R"(],
  "outputs": ["k.out"]
})";
    auto g = RenderGraph::parse(text, kFile);
    loom::json before = g->getParam("k.outputs");
    try {
        // An output named like the existing input is rejected...
        g->setParam("k.outputs", {{"in", {{"format", "rgba32f"}}}});
        FAIL() << "duplicate port accepted";
    } catch (const loom::UserError& e) {
        EXPECT_NE(std::string(e.what()).find("port name 'in' is declared twice"), std::string::npos)
            << e.what();
    }
    // ...and leaves the pass exactly as it was: same parameter, same ports, still compiles.
    EXPECT_EQ(g->getParam("k.outputs"), before);
    auto refl = g->findPass("k")->reflection();
    ASSERT_EQ(refl.ports().size(), 2u);
    EXPECT_EQ(refl.ports()[1].name, "out");
    auto cg = g->compile(4, 4);
    EXPECT_EQ(cg.portResource.count("k.out"), 1u);
}

TEST(GraphValidation, RejectedImagePathKeepsTheImageSize) {
    loom::test::TempDir tmp("loom-validation");
    loom::writeImage(tmp / "small.exr", loom::ImageData::make(5, 3, 4, 0.5f));
    const std::string text = R"({
  "passes": [{"name": "src", "type": "ImageLoader", "params": {"path": "small.exr"}},
             {"name": "tm", "type": "ToneMap"}],
  "edges": [["src.output", "tm.input"]],
  "outputs": ["tm.output"]
})";
    auto g = RenderGraph::parse(text, tmp / "graph.json");
    auto size = [&] {
        auto cg = g->compile(16, 16);
        const auto& r = cg.resources[cg.portResource.at("src.output")];
        return std::make_pair(r.width, r.height);
    };
    EXPECT_EQ(size(), std::make_pair(5u, 3u));
    try {
        g->setParam("src.path", "missing.exr");
        FAIL() << "missing image accepted";
    } catch (const loom::UserError& e) {
        EXPECT_NE(std::string(e.what()).find("parameter 'path': missing.exr"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(g->getParam("src.path"), "small.exr");
    EXPECT_EQ(size(), std::make_pair(5u, 3u)) << "the loader forgot its image's size";
}

TEST(GraphValidation, EdgeMixingPortAndPass) {
    const std::string text = R"({
  "passes": [{"name": "a", "type": "ImageLoader"}, {"name": "tm", "type": "ToneMap"}],
  "edges": [["a.output", "tm"]],
  "outputs": ["tm.output"]
})";
    expectMessage(parseError(text), locationOf(kFile, text, "[\"a.output\""),
                  {"edge mixes a port and a pass"});
}

TEST(GraphValidation, LoadNamesMissingFile) {
    try {
        RenderGraph::load("/nonexistent/graph.json");
        FAIL() << "missing file accepted";
    } catch (const GraphError& e) {
        EXPECT_STREQ(e.what(), "/nonexistent/graph.json: cannot open graph file");
    }
}

TEST(GraphValidation, EditingValidatesImmediately) {
    const std::string text = R"({
  "passes": [{"name": "src", "type": "ImageLoader"}, {"name": "tm", "type": "ToneMap"}],
  "edges": [["src.output", "tm.input"]],
  "outputs": ["tm.output"]
})";
    auto g = RenderGraph::parse(text, kFile);
    EXPECT_THROW(g->connect("src.output", "tm.nope"), GraphError);
    EXPECT_EQ(g->edges().size(), 1u);  // the rejected edge is not kept
    EXPECT_THROW(g->markOutput("tm.missing"), GraphError);
    EXPECT_EQ(g->outputs().size(), 1u);
    try {
        g->setParam("tm.exposure", 99.0);
        FAIL() << "out-of-range value accepted";
    } catch (const loom::UserError& e) {
        EXPECT_NE(std::string(e.what()).find("'exposure' = 99 is out of range"), std::string::npos);
    }
    EXPECT_EQ(g->getParam("tm.exposure"), 0.0);  // unchanged
}

}  // namespace
