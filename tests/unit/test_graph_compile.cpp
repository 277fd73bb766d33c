// Graph compile stages without a GPU: order, culling, allocation and aliasing. Shapes are
// built from JSON-declared ComputePasses, whose ports come from their parameters.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "core/graph/RenderGraph.h"
#include "tests/support/ComputeGraphText.h"

namespace {

using loom::CompiledGraph;
using loom::RenderGraph;

struct Node {
    std::string name;
    std::vector<std::string> inputs;   // rgba32f texture inputs
    std::vector<std::string> outputs;  // rgba32f texture outputs (unless format given below)
    std::string outputFormat = "rgba32f";
    bool optionalOutputs = false;
};

std::string graphText(const std::vector<Node>& nodes,
                      const std::vector<std::pair<std::string, std::string>>& edges,
                      const std::vector<std::string>& outputs) {
    std::vector<loom::test::ComputeNodeSpec> specs;
    for (const auto& n : nodes)
        specs.push_back({n.name, n.inputs, {}, n.outputs, n.outputFormat, n.optionalOutputs});
    return loom::test::computeGraphText("shape", specs, edges, outputs);
}

std::unique_ptr<RenderGraph> build(const std::vector<Node>& nodes,
                                   const std::vector<std::pair<std::string, std::string>>& edges,
                                   const std::vector<std::string>& outputs) {
    return RenderGraph::parse(graphText(nodes, edges, outputs), "shape.json");
}

std::vector<std::string> orderNames(const RenderGraph& g, const CompiledGraph& cg) {
    std::vector<std::string> names;
    for (int i : cg.order) names.push_back(g.passes()[i]->name());
    return names;
}

const CompiledGraph::Resource& resource(const CompiledGraph& cg, const std::string& port) {
    auto it = cg.portResource.find(port);
    if (it == cg.portResource.end()) throw std::runtime_error("no resource for " + port);
    return cg.resources[it->second];
}

// A -> B -> C -> D, each with input "in" and output "out"; declared in `declOrder`.
std::unique_ptr<RenderGraph> chain(const std::vector<std::string>& declOrder,
                                   std::vector<std::pair<std::string, std::string>> extra = {},
                                   std::vector<std::string> outputs = {"D.out"}) {
    std::vector<Node> nodes;
    for (auto& n : declOrder)
        nodes.push_back(
            {n, n == "A" ? std::vector<std::string>{} : std::vector<std::string>{"in"}, {"out"}});
    std::vector<std::pair<std::string, std::string>> edges{
        {"A.out", "B.in"}, {"B.out", "C.in"}, {"C.out", "D.in"}};
    edges.insert(edges.end(), extra.begin(), extra.end());
    return build(nodes, edges, outputs);
}

TEST(GraphCompile, TopologicalOrderFollowsEdgesNotDeclaration) {
    auto g = chain({"D", "C", "B", "A"});
    auto cg = g->compile(8, 8);
    EXPECT_EQ(orderNames(*g, cg), (std::vector<std::string>{"A", "B", "C", "D"}));
    EXPECT_TRUE(cg.culled.empty());
}

TEST(GraphCompile, TiesKeepDeclarationOrder) {
    // Independent sources feed one sink: the sources keep their declared order.
    auto g =
        build({{"s2", {}, {"out"}},
               {"s1", {}, {"out"}},
               {"s3", {}, {"out"}},
               {"sink", {"a", "b", "c"}, {"out"}}},
              {{"s1.out", "sink.a"}, {"s2.out", "sink.b"}, {"s3.out", "sink.c"}}, {"sink.out"});
    EXPECT_EQ(orderNames(*g, g->compile(8, 8)),
              (std::vector<std::string>{"s2", "s1", "s3", "sink"}));
}

TEST(GraphCompile, ExecutionOnlyEdgesOrderAndKeepPasses) {
    // "late" is declared first and writes no consumed port, but must run after "early"; the
    // execution-only edge early -> late also keeps "early" alive although nothing reads it.
    auto g =
        build({{"late", {}, {"out"}}, {"early", {}, {"side"}}}, {{"early", "late"}}, {"late.out"});
    auto cg = g->compile(8, 8);
    EXPECT_EQ(orderNames(*g, cg), (std::vector<std::string>{"early", "late"}));
    EXPECT_TRUE(cg.culled.empty());
}

TEST(GraphCompile, CullingRemovesPassesThatFeedNoOutput) {
    // A -> B -> C -> D with an extra branch B -> E -> F that reaches no output, and G alone.
    auto g = build({{"A", {}, {"out"}},
                    {"B", {"in"}, {"out"}},
                    {"C", {"in"}, {"out"}},
                    {"D", {"in"}, {"out"}},
                    {"E", {"in"}, {"out"}},
                    {"F", {"in"}, {"out"}},
                    {"G", {}, {"out"}}},
                   {{"A.out", "B.in"},
                    {"B.out", "C.in"},
                    {"C.out", "D.in"},
                    {"B.out", "E.in"},
                    {"E.out", "F.in"}},
                   {"D.out"});
    auto cg = g->compile(8, 8);
    EXPECT_EQ(orderNames(*g, cg), (std::vector<std::string>{"A", "B", "C", "D"}));
    EXPECT_EQ(cg.culled, (std::vector<std::string>{"E", "F", "G"}));
    // Culled passes get no resources, and B.out's lifetime ignores the culled reader E.
    EXPECT_EQ(cg.portResource.count("E.out"), 0u);
    EXPECT_EQ(cg.portResource.count("E.in"), 0u);
    EXPECT_EQ(resource(cg, "B.out").lastUse, 2);

    // Marking F's output keeps the branch.
    g->markOutput("F.out");
    auto cg2 = g->compile(8, 8);
    EXPECT_EQ(cg2.culled, (std::vector<std::string>{"G"}));
    EXPECT_EQ(resource(cg2, "B.out").lastUse, 4);  // read by E at position 4 (A B C D E F)
}

TEST(GraphCompile, InputsShareTheirProducersResource) {
    auto g = chain({"A", "B", "C", "D"});
    auto cg = g->compile(8, 8);
    EXPECT_EQ(cg.portResource.at("B.in"), cg.portResource.at("A.out"));
    EXPECT_EQ(cg.portResource.at("D.in"), cg.portResource.at("C.out"));
    const auto& a = resource(cg, "A.out");
    EXPECT_EQ(a.width, 8u);
    EXPECT_EQ(a.height, 8u);
    EXPECT_EQ(a.firstUse, 0);
    EXPECT_EQ(a.lastUse, 1);
}

TEST(GraphCompile, ChainAliasesDisjointLifetimes) {
    // Lifetimes: A.out [0,1], B.out [1,2], C.out [2,3], D.out (graph output) [3,4].
    auto g = chain({"A", "B", "C", "D"});
    auto cg = g->compile(8, 8);
    const auto &a = resource(cg, "A.out"), &b = resource(cg, "B.out"), &c = resource(cg, "C.out"),
               &d = resource(cg, "D.out");
    EXPECT_EQ(a.physical, c.physical) << "A.out is dead before C writes";
    EXPECT_NE(a.physical, b.physical) << "B reads A.out while writing B.out";
    EXPECT_NE(b.physical, c.physical) << "C reads B.out while writing C.out";
    EXPECT_NE(d.physical, a.physical);
    EXPECT_NE(d.physical, b.physical);
    EXPECT_TRUE(d.graphOutput);
    EXPECT_EQ(d.lastUse, 4);
    EXPECT_EQ(cg.resources.size(), 4u);
    EXPECT_EQ(cg.physicalCount, 3);
}

TEST(GraphCompile, LongChainReusesTwoTransients) {
    std::vector<Node> nodes{{"n0", {}, {"out"}}};
    std::vector<std::pair<std::string, std::string>> edges;
    for (int i = 1; i < 8; ++i) {
        nodes.push_back({"n" + std::to_string(i), {"in"}, {"out"}});
        edges.push_back({"n" + std::to_string(i - 1) + ".out", "n" + std::to_string(i) + ".in"});
    }
    auto g = build(nodes, edges, {"n7.out"});
    auto cg = g->compile(8, 8);
    // Ping-pong between two transients, plus the graph output.
    EXPECT_EQ(cg.physicalCount, 3);
    for (int i = 0; i + 2 < 7; ++i)
        EXPECT_EQ(resource(cg, "n" + std::to_string(i) + ".out").physical,
                  resource(cg, "n" + std::to_string(i + 2) + ".out").physical);
}

TEST(GraphCompile, OverlappingLifetimesNeverAlias) {
    // A.out is also read by D (position 3), so it is alive while B.out and C.out exist.
    std::vector<Node> nodes{{"A", {}, {"out"}},
                            {"B", {"in"}, {"out"}},
                            {"C", {"in"}, {"out"}},
                            {"D", {"in", "skip"}, {"out"}}};
    auto g =
        build(nodes, {{"A.out", "B.in"}, {"B.out", "C.in"}, {"C.out", "D.in"}, {"A.out", "D.skip"}},
              {"D.out"});
    auto cg = g->compile(8, 8);
    const auto &a = resource(cg, "A.out"), &b = resource(cg, "B.out"), &c = resource(cg, "C.out");
    EXPECT_EQ(a.lastUse, 3);
    EXPECT_NE(a.physical, b.physical);
    EXPECT_NE(a.physical, c.physical);
    EXPECT_NE(b.physical, c.physical);
    EXPECT_EQ(cg.physicalCount, 4);

    // Any two resources sharing memory must have disjoint lifetimes.
    for (size_t i = 0; i < cg.resources.size(); ++i)
        for (size_t j = i + 1; j < cg.resources.size(); ++j) {
            const auto &x = cg.resources[i], &y = cg.resources[j];
            if (x.physical != y.physical) continue;
            EXPECT_TRUE(x.lastUse < y.firstUse || y.lastUse < x.firstUse)
                << x.name << " and " << y.name << " overlap";
        }
}

TEST(GraphCompile, DifferentDescriptionsNeverAlias) {
    // Same lifetimes as the aliasing chain, but C writes r32f: A.out (rgba32f) cannot host it.
    std::vector<Node> nodes{{"A", {}, {"out"}},
                            {"B", {"in"}, {"out"}},
                            {"C", {"in"}, {"out"}, "r32f"},
                            {"D", {}, {"out"}}};
    auto text = graphText(nodes, {{"A.out", "B.in"}, {"B.out", "C.in"}, {"C", "D"}}, {"D.out"});
    // C.out is consumed by nobody but is not optional: still allocated (the shader writes it).
    auto g = RenderGraph::parse(text, "shape.json");
    auto cg = g->compile(8, 8);
    EXPECT_EQ(resource(cg, "C.out").format, loom::gpu::Format::R32F);
    EXPECT_NE(resource(cg, "C.out").physical, resource(cg, "A.out").physical);
}

TEST(GraphCompile, GraphOutputsNeverAlias) {
    // A.out is a marked output read only by B; without the mark it would host C.out.
    auto g = chain({"A", "B", "C", "D"}, {}, {"D.out", "A.out"});
    auto cg = g->compile(8, 8);
    const auto &a = resource(cg, "A.out"), &c = resource(cg, "C.out");
    EXPECT_TRUE(a.graphOutput);
    EXPECT_EQ(a.lastUse, 4);
    EXPECT_NE(a.physical, c.physical);
    for (const auto& r : cg.resources) {
        if (&r == &a) continue;
        EXPECT_NE(r.physical, a.physical) << r.name;
    }
}

TEST(GraphCompile, PersistentResourcesNeverAlias) {
    const std::string text = R"({
  "passes": [
    {"name": "gen", "type": "ComputePass", "params": {"shader": "g.comp",
      "outputs": {"out": {}}}},
    {"name": "acc", "type": "Accumulate"},
    {"name": "k1", "type": "ComputePass", "params": {"shader": "k.comp",
      "inputs": {"in": {}}, "outputs": {"out": {}}}},
    {"name": "k2", "type": "ComputePass", "params": {"shader": "k.comp",
      "inputs": {"in": {}}, "outputs": {"out": {}}, "persistent": {"hist": {}}}},
    {"name": "k3", "type": "ComputePass", "params": {"shader": "k.comp",
      "inputs": {"in": {}}, "outputs": {"out": {}}}}
  ],
  "edges": [["gen.out", "acc.input"], ["acc.output", "k1.in"], ["k1.out", "k2.in"],
            ["k2.out", "k3.in"]],
  "outputs": ["k3.out"]
})";
    auto g = RenderGraph::parse(text, "persist.json");
    auto cg = g->compile(8, 4);
    std::vector<std::string> persistent;
    for (const auto& r : cg.resources) {
        if (!r.persistent) continue;
        persistent.push_back(r.name);
        EXPECT_EQ(r.width, 8u);
        EXPECT_EQ(r.height, 4u);
        EXPECT_EQ(r.firstUse, 0);
        EXPECT_EQ(r.lastUse, int(cg.order.size()));
        for (const auto& o : cg.resources) {
            if (&o == &r) continue;
            EXPECT_NE(o.physical, r.physical) << r.name << " aliases " << o.name;
        }
    }
    EXPECT_EQ(persistent, (std::vector<std::string>{"acc#mean", "acc#m2", "k2#hist"}));
    // The transients still alias among themselves: gen.out [0,1] hosts k1.out [2,3].
    EXPECT_EQ(resource(cg, "gen.out").physical, resource(cg, "k1.out").physical);
}

TEST(GraphCompile, OptionalOutputsOnlyWhenConsumedOrMarked) {
    const std::string base = R"({
  "passes": [
    {"name": "gen", "type": "ComputePass", "params": {"shader": "g.comp",
      "outputs": {"out": {}}}},
    {"name": "acc", "type": "Accumulate"},
    {"name": "tm", "type": "ToneMap"}
  ],
  "edges": [["gen.out", "acc.input"], ["acc.output", "tm.input"]],
  "outputs": ["tm.output"]
})";
    auto g = RenderGraph::parse(base, "opt.json");
    auto cg = g->compile(8, 8);
    EXPECT_EQ(cg.portResource.count("acc.variance"), 0u);
    for (const auto& r : cg.resources) EXPECT_NE(r.name, "acc.variance");

    g->markOutput("acc.variance");
    cg = g->compile(8, 8);
    ASSERT_EQ(cg.portResource.count("acc.variance"), 1u);
    EXPECT_TRUE(resource(cg, "acc.variance").graphOutput);

    g->unmarkOutput("acc.variance");
    g->addPass("ToneMap", "tmVar");
    g->connect("acc.variance", "tmVar.input");
    g->markOutput("tmVar.output");
    cg = g->compile(8, 8);
    ASSERT_EQ(cg.portResource.count("acc.variance"), 1u);
    EXPECT_FALSE(resource(cg, "acc.variance").graphOutput);
    EXPECT_EQ(cg.portResource.at("tmVar.input"), cg.portResource.at("acc.variance"));

    // A consumer that is culled does not count.
    g->unmarkOutput("tmVar.output");
    cg = g->compile(8, 8);
    EXPECT_EQ(cg.culled, (std::vector<std::string>{"tmVar"}));
    EXPECT_EQ(cg.portResource.count("acc.variance"), 0u);
}

TEST(GraphCompile, SizeRules) {
    const std::string text = R"({
  "passes": [
    {"name": "k", "type": "ComputePass", "params": {"shader": "k.comp",
      "outputs": {"half": {"scale": 0.5}, "fixed": {"size": [3, 5], "format": "r32ui"},
                  "buf": {"kind": "buffer", "bytesPerPixel": 16},
                  "hdr": {"kind": "buffer", "bytes": 64}}}}
  ],
  "outputs": ["k.half"]
})";
    auto g = RenderGraph::parse(text, "size.json");
    auto cg = g->compile(10, 7);
    EXPECT_EQ(resource(cg, "k.half").width, 5u);
    EXPECT_EQ(resource(cg, "k.half").height, 4u);  // lround(3.5)
    EXPECT_EQ(resource(cg, "k.fixed").width, 3u);
    EXPECT_EQ(resource(cg, "k.fixed").height, 5u);
    EXPECT_EQ(resource(cg, "k.fixed").format, loom::gpu::Format::R32UI);
    EXPECT_EQ(resource(cg, "k.buf").bytes, 16u * 10 * 7);
    EXPECT_EQ(resource(cg, "k.hdr").bytes, 64u);
    EXPECT_THROW(g->compile(0, 7), loom::GraphError);
}

TEST(GraphCompile, GraphvizNamesPassesAndEdges) {
    auto g = build({{"A", {}, {"out"}}, {"B", {"in"}, {"out"}}}, {{"A.out", "B.in"}, {"A", "B"}},
                   {"B.out"});
    std::string dot = g->toGraphviz();
    EXPECT_NE(dot.find("\"A\" -> \"B\" [label=\"out -> in\"]"), std::string::npos) << dot;
    EXPECT_NE(dot.find("\"A\" -> \"B\" [style=dashed]"), std::string::npos) << dot;
    EXPECT_NE(dot.find("\"out:B.out\""), std::string::npos) << dot;
}

}  // namespace
