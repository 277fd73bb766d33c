// Inspector graph view: automatic left-to-right layout by topological depth. No window, no GPU.
#include <gtest/gtest.h>

#include "apps/inspector/GraphLayout.h"
#include "core/graph/RenderGraph.h"

namespace {

using loom::RenderGraph;
using loom::inspector::GraphLayout;
using loom::inspector::layoutGraph;

std::unique_ptr<RenderGraph> parse(const std::string& text) {
    return RenderGraph::parse(text, "layout.json");
}

// Boxes never overlap (with the style's gaps they would not even touch).
void expectNoOverlap(const GraphLayout& l) {
    for (size_t i = 0; i < l.nodes.size(); ++i)
        for (size_t j = i + 1; j < l.nodes.size(); ++j) {
            const auto& a = l.nodes[i];
            const auto& b = l.nodes[j];
            bool apart = a.x + a.width <= b.x || b.x + b.width <= a.x || a.y + a.height <= b.y ||
                         b.y + b.height <= a.y;
            EXPECT_TRUE(apart) << a.pass << " overlaps " << b.pass;
        }
}

TEST(InspectorLayout, ChainGoesLeftToRight) {
    auto g = parse(R"({"passes": [
        {"name": "tm", "type": "ToneMap"},
        {"name": "accum", "type": "Accumulate"},
        {"name": "tm2", "type": "ToneMap"}],
      "edges": [["accum.output", "tm.input"], ["tm.output", "tm2.input"]],
      "outputs": ["tm2.output"]})");
    // accum has an unconnected required input: layout works on any graph structure.
    GraphLayout l = layoutGraph(*g);
    ASSERT_EQ(l.nodes.size(), 3u);
    const auto& tm = l.nodes[l.findNode("tm")];
    const auto& accum = l.nodes[l.findNode("accum")];
    const auto& tm2 = l.nodes[l.findNode("tm2")];
    EXPECT_EQ(accum.column, 0);
    EXPECT_EQ(tm.column, 1);
    EXPECT_EQ(tm2.column, 2);
    EXPECT_LT(accum.x + accum.width, tm.x);
    EXPECT_LT(tm.x + tm.width, tm2.x);
    EXPECT_GE(l.width, tm2.x + tm2.width);
    EXPECT_GE(l.height, tm2.y + tm2.height);
    expectNoOverlap(l);
}

TEST(InspectorLayout, PinsEdgesAndOutputs) {
    auto g = parse(R"({"passes": [
        {"name": "accum", "type": "Accumulate"},
        {"name": "tm", "type": "ToneMap"}],
      "edges": [["accum.output", "tm.input"]],
      "outputs": ["tm.output", "accum.variance"]})");
    GraphLayout l = layoutGraph(*g);
    const auto& accum = l.nodes[l.findNode("accum")];
    const auto& tm = l.nodes[l.findNode("tm")];
    // Ports from the declarations: inputs on the left edge, outputs on the right edge.
    ASSERT_NE(accum.findPin("input", true), nullptr);
    ASSERT_NE(accum.findPin("output", false), nullptr);
    ASSERT_NE(accum.findPin("variance", false), nullptr);
    EXPECT_EQ(accum.findPin("input", true)->x, accum.x);
    EXPECT_EQ(accum.findPin("output", false)->x, accum.x + accum.width);
    for (const auto* pin : {accum.findPin("output", false), accum.findPin("variance", false)}) {
        EXPECT_GT(pin->y, accum.y);
        EXPECT_LT(pin->y, accum.y + accum.height);
    }
    // Graph outputs are marked on their pins.
    EXPECT_TRUE(tm.findPin("output", false)->graphOutput);
    EXPECT_TRUE(accum.findPin("variance", false)->graphOutput);
    EXPECT_FALSE(accum.findPin("output", false)->graphOutput);
    // The edge joins the right pins.
    ASSERT_EQ(l.edges.size(), 1u);
    const auto& e = l.edges[0];
    EXPECT_EQ(l.nodes[e.src].outputs[e.srcPin].port, "output");
    EXPECT_EQ(l.nodes[e.dst].inputs[e.dstPin].port, "input");
    EXPECT_FALSE(e.backEdge);
}

TEST(InspectorLayout, DiamondAndParallelBranches) {
    // a -> b, a -> c, (b, c) -> d with execution-only edges; b and c share a column.
    auto g = parse(R"({"passes": [
        {"name": "a", "type": "ToneMap"}, {"name": "b", "type": "ToneMap"},
        {"name": "c", "type": "ToneMap"}, {"name": "d", "type": "ToneMap"},
        {"name": "lonely", "type": "Accumulate"}],
      "edges": [["a", "b"], ["a", "c"], ["b", "d"], ["c", "d"]],
      "outputs": ["d.output"]})");
    GraphLayout l = layoutGraph(*g);
    auto col = [&](const char* n) { return l.nodes[l.findNode(n)].column; };
    EXPECT_EQ(col("a"), 0);
    EXPECT_EQ(col("b"), 1);
    EXPECT_EQ(col("c"), 1);
    EXPECT_EQ(col("d"), 2);
    EXPECT_EQ(col("lonely"), 0);
    for (const auto& e : l.edges) {
        EXPECT_EQ(e.srcPin, -1);  // execution-only
        EXPECT_EQ(e.dstPin, -1);
    }
    expectNoOverlap(l);
    // Deterministic.
    GraphLayout again = layoutGraph(*g);
    for (size_t i = 0; i < l.nodes.size(); ++i) {
        EXPECT_EQ(l.nodes[i].x, again.nodes[i].x);
        EXPECT_EQ(l.nodes[i].y, again.nodes[i].y);
    }
}

TEST(InspectorLayout, ProjectGraphsLayOut) {
    for (const char* name : {"pt.json", "hello_compute.json"}) {
        auto g = RenderGraph::load(std::string(LOOM_SOURCE_DIR) + "/graphs/" + name);
        GraphLayout l = layoutGraph(*g);
        EXPECT_EQ(l.nodes.size(), g->passes().size()) << name;
        EXPECT_EQ(l.edges.size(), g->edges().size()) << name;
        expectNoOverlap(l);
        // Every data edge runs left to right in a DAG.
        for (const auto& e : l.edges) {
            EXPECT_FALSE(e.backEdge) << name;
            EXPECT_LT(l.nodes[e.src].column, l.nodes[e.dst].column) << name;
        }
    }
}

}  // namespace
