// Previous-frame inputs (temporal feedback edges) without a GPU: an edge into an input declared
// previousFrame() closes loops and may be a self-edge, imposes no ordering, gets a persistent
// "src.port@prev" history copy, and keeps its source alive (unaliased) until the end-of-frame
// copy. Ordinary self-edges and cycles are still rejected with the usual messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "core/graph/RenderGraph.h"
#include "tests/support/ComputeGraphText.h"

namespace {

using loom::CompiledGraph;
using loom::GraphError;
using loom::json;
using loom::RenderGraph;

const std::string kSource = LOOM_SOURCE_DIR;

struct Node {
    std::string name;
    std::vector<std::string> inputs;      // rgba32f texture inputs
    std::vector<std::string> prevInputs;  // rgba32f texture inputs with "previousFrame": true
    std::vector<std::string> outputs;     // rgba32f texture outputs
};

std::string graphText(const std::vector<Node>& nodes,
                      const std::vector<std::pair<std::string, std::string>>& edges,
                      const std::vector<std::string>& outputs) {
    std::vector<loom::test::ComputeNodeSpec> specs;
    for (const auto& n : nodes) specs.push_back({n.name, n.inputs, n.prevInputs, n.outputs});
    return loom::test::computeGraphText("feedback", specs, edges, outputs);
}

std::unique_ptr<RenderGraph> build(const std::vector<Node>& nodes,
                                   const std::vector<std::pair<std::string, std::string>>& edges,
                                   const std::vector<std::string>& outputs) {
    return RenderGraph::parse(graphText(nodes, edges, outputs), "feedback.json");
}

// The GraphError message of parsing (validation runs on parse); fails when none is thrown.
std::string parseError(const std::vector<Node>& nodes,
                       const std::vector<std::pair<std::string, std::string>>& edges,
                       const std::vector<std::string>& outputs) {
    try {
        build(nodes, edges, outputs);
    } catch (const GraphError& e) {
        return e.what();
    }
    ADD_FAILURE() << "graph was accepted:\n" << graphText(nodes, edges, outputs);
    return "";
}

std::vector<std::string> orderNames(const RenderGraph& g, const CompiledGraph& cg) {
    std::vector<std::string> names;
    for (int i : cg.order) names.push_back(g.passes()[i]->name());
    return names;
}

int resourceIndex(const CompiledGraph& cg, const std::string& key) {
    auto it = cg.portResource.find(key);
    if (it == cg.portResource.end()) throw std::runtime_error("no resource for " + key);
    return it->second;
}

// No other resource shares the physical memory of resource `ri`.
void expectUnaliased(const CompiledGraph& cg, int ri) {
    const auto& r = cg.resources[ri];
    for (size_t o = 0; o < cg.resources.size(); ++o) {
        if (int(o) == ri) continue;
        EXPECT_NE(cg.resources[o].physical, r.physical)
            << r.name << " shares memory with " << cg.resources[o].name;
    }
}

// A feedback source lives to the end of the frame (the history copy reads it then): memory it
// shares must belong to resources whose lifetime ended before it was produced.
void expectLivesToFrameEnd(const CompiledGraph& cg, int ri) {
    const auto& r = cg.resources[ri];
    EXPECT_EQ(r.lastUse, int(cg.order.size())) << r.name;
    for (size_t o = 0; o < cg.resources.size(); ++o) {
        const auto& other = cg.resources[o];
        if (int(o) == ri || other.physical != r.physical) continue;
        EXPECT_LT(other.lastUse, r.firstUse) << r.name << " shares memory with " << other.name;
    }
}

TEST(GraphFeedback, FeedbackEdgeClosingALoopIsAccepted) {
    // a -> b ordinarily, b -> a.hist into a previous-frame input: a loop of edges, but only
    // the ordinary edge orders the passes (b is declared first and still runs second).
    auto g = build({{"b", {"in"}, {}, {"out"}}, {"a", {}, {"hist"}, {"out"}}},
                   {{"a.out", "b.in"}, {"b.out", "a.hist"}}, {"b.out"});
    auto cg = g->compile(8, 8);
    EXPECT_EQ(orderNames(*g, cg), (std::vector<std::string>{"a", "b"}));
    EXPECT_TRUE(cg.culled.empty());
}

TEST(GraphFeedback, SelfEdgeIntoPreviousFrameInputIsAccepted) {
    auto g = build({{"p", {}, {"prev"}, {"out"}}}, {{"p.out", "p.prev"}}, {"p.out"});
    auto cg = g->compile(8, 8);
    EXPECT_EQ(orderNames(*g, cg), (std::vector<std::string>{"p"}));
    int src = resourceIndex(cg, "p.out");
    int hist = resourceIndex(cg, "p.out@prev");
    EXPECT_EQ(resourceIndex(cg, "p.prev"), hist);
    EXPECT_EQ(cg.resources[hist].historyOf, src);
    EXPECT_NE(cg.resources[hist].physical, cg.resources[src].physical);
}

TEST(GraphFeedback, OrdinarySelfEdgeIsStillRejected) {
    // The same pass with its ordinary input wired to itself.
    std::string msg = parseError({{"p", {"in"}, {"prev"}, {"out"}}},
                                 {{"p.out", "p.in"}, {"p.out", "p.prev"}}, {"p.out"});
    EXPECT_NE(msg.find("pass 'p' is connected to itself"), std::string::npos) << msg;
    // Execution-only self-edges are not feedback edges either.
    msg = parseError({{"p", {}, {"prev"}, {"out"}}}, {{"p", "p"}}, {"p.out"});
    EXPECT_NE(msg.find("pass 'p' is connected to itself"), std::string::npos) << msg;
}

TEST(GraphFeedback, OrdinaryCycleIsStillRejected) {
    // x -> y -> z -> x through ordinary inputs; the feedback edge y -> x.hist does not excuse it.
    std::string msg = parseError(
        {{"x", {"in"}, {"hist"}, {"out"}}, {"y", {"in"}, {}, {"out"}}, {"z", {"in"}, {}, {"out"}}},
        {{"x.out", "y.in"}, {"y.out", "z.in"}, {"z.out", "x.in"}, {"y.out", "x.hist"}}, {"z.out"});
    EXPECT_NE(msg.find("graph has a cycle: "), std::string::npos) << msg;
    for (const char* n : {"x", "y", "z"})
        EXPECT_NE(msg.find(n), std::string::npos) << n << " not named in: " << msg;
    // The same two passes in a loop without a previous-frame input: a cycle.
    msg = parseError({{"a", {"in"}, {}, {"out"}}, {"b", {"in"}, {}, {"out"}}},
                     {{"a.out", "b.in"}, {"b.out", "a.in"}}, {"b.out"});
    EXPECT_NE(msg.find("graph has a cycle: "), std::string::npos) << msg;
}

TEST(GraphFeedback, HistoryResourceIsPersistentAndSourceIsNotAliased) {
    // A -> B -> C -> D -> E. Without feedback A.out [0,1] would share memory with C.out [2,3]
    // (GraphCompile.ChainAliasesDisjointLifetimes); C reads A.out of the previous frame, so
    // A.out must live to the end of the frame, when it is copied into A.out@prev.
    auto g = build({{"A", {}, {}, {"out"}},
                    {"B", {"in"}, {}, {"out"}},
                    {"C", {"in"}, {"prev"}, {"out"}},
                    {"D", {"in"}, {}, {"out"}},
                    {"E", {"in"}, {}, {"out"}}},
                   {{"A.out", "B.in"},
                    {"B.out", "C.in"},
                    {"C.out", "D.in"},
                    {"D.out", "E.in"},
                    {"A.out", "C.prev"}},
                   {"E.out"});
    auto cg = g->compile(16, 8);
    const int end = int(cg.order.size());
    int src = resourceIndex(cg, "A.out");
    int hist = resourceIndex(cg, "A.out@prev");
    const auto& h = cg.resources[hist];
    EXPECT_EQ(h.name, "A.out@prev");
    EXPECT_TRUE(h.persistent);
    EXPECT_FALSE(h.graphOutput);
    EXPECT_EQ(h.historyOf, src);
    EXPECT_EQ(h.firstUse, 0);
    EXPECT_EQ(h.lastUse, end);
    // Same description as the source, so the copy is a plain image copy.
    EXPECT_EQ(h.kind, cg.resources[src].kind);
    EXPECT_EQ(h.format, cg.resources[src].format);
    EXPECT_EQ(h.width, 16u);
    EXPECT_EQ(h.height, 8u);
    // The previous-frame input reads the copy; the ordinary input the producer's resource.
    EXPECT_EQ(resourceIndex(cg, "C.prev"), hist);
    EXPECT_EQ(resourceIndex(cg, "B.in"), src);
    EXPECT_EQ(cg.resources[src].historyOf, -1);
    EXPECT_FALSE(cg.resources[src].persistent);
    expectLivesToFrameEnd(cg, src);
    expectUnaliased(cg, src);  // A runs first: nothing ended before it
    expectUnaliased(cg, hist);
    // Only one history resource exists, and only feedback sources have one.
    int histories = 0;
    for (const auto& r : cg.resources) histories += r.historyOf >= 0;
    EXPECT_EQ(histories, 1);
    // Transients that are not feedback sources still alias (B.out [1,2] hosts D.out [3,4]).
    EXPECT_EQ(cg.resources[resourceIndex(cg, "B.out")].physical,
              cg.resources[resourceIndex(cg, "D.out")].physical);
}

TEST(GraphFeedback, FeedbackConsumersShareOneHistoryCopy) {
    auto g = build(
        {{"src", {}, {}, {"out"}},
         {"u", {"in"}, {"prev"}, {"out"}},
         {"v", {"in"}, {"prev"}, {"out"}}},
        {{"src.out", "u.in"}, {"u.out", "v.in"}, {"src.out", "u.prev"}, {"src.out", "v.prev"}},
        {"v.out"});
    auto cg = g->compile(4, 4);
    int hist = resourceIndex(cg, "src.out@prev");
    EXPECT_EQ(resourceIndex(cg, "u.prev"), hist);
    EXPECT_EQ(resourceIndex(cg, "v.prev"), hist);
    std::set<std::string> names;
    for (const auto& r : cg.resources)
        if (r.historyOf >= 0) names.insert(r.name);
    EXPECT_EQ(names, (std::set<std::string>{"src.out@prev"}));
}

TEST(GraphFeedback, ProducerFeedingOnlyAFeedbackEdgeIsKept) {
    // "late" runs after "main" in the order (no ordinary edge between them) and exists only to
    // feed main's previous-frame input: culling follows feedback edges too.
    auto g = build({{"main", {}, {"prev"}, {"out"}}, {"late", {}, {}, {"out"}}},
                   {{"late.out", "main.prev"}}, {"main.out"});
    auto cg = g->compile(4, 4);
    EXPECT_TRUE(cg.culled.empty());
    EXPECT_EQ(orderNames(*g, cg), (std::vector<std::string>{"main", "late"}));
    EXPECT_EQ(cg.resources[resourceIndex(cg, "main.prev")].historyOf,
              resourceIndex(cg, "late.out"));
}

TEST(GraphFeedback, ComputePassPreviousFrameFieldIsValidated) {
    auto expectError = [](const std::string& port, const std::string& expected) {
        const std::string text =
            R"({"passes": [{"name": "k", "type": "ComputePass", "params": {"shader": "k.comp",
            "outputs": {"out": {}}, )" +
            port + "}}], \"outputs\": [\"k.out\"]}";
        try {
            RenderGraph::parse(text, "bad.json");
            ADD_FAILURE() << "accepted: " << text;
        } catch (const GraphError& e) {
            EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
        }
    };
    expectError(R"("inputs": {"h": {"previousFrame": 1}})",
                "input 'h': 'previousFrame' must be a bool");
    expectError(R"("persistent": {"h": {"previousFrame": true}})",
                "persistent 'h': 'previousFrame' applies to inputs only");
    // The declaration reaches the pass's reflection and survives the JSON round trip.
    auto g = build({{"p", {}, {"prev"}, {"out"}}}, {{"p.out", "p.prev"}}, {"p.out"});
    auto refl = g->findPass("p")->reflection();
    ASSERT_NE(refl.findPort("prev"), nullptr);
    EXPECT_TRUE(refl.findPort("prev")->previousFrame);
    EXPECT_FALSE(refl.findPort("out")->previousFrame);
    auto again = RenderGraph::parse(g->toJson().dump(2), "again.json");
    EXPECT_TRUE(g->equals(*again));
    EXPECT_TRUE(again->findPass("p")->reflection().findPort("prev")->previousFrame);
}

TEST(GraphFeedback, ReSTIRPTGraphsKeepHistoryOfTheLastReuseStage) {
    struct Expect {
        const char* graph;
        const char* prevReservoirs;  // source of temporal.prevReservoirs
    };
    for (auto e : {Expect{"graphs/restir_pt.json", "spatial.reservoirsOut"},
                   Expect{"graphs/restir_pt_temporal_only.json", "temporal.reservoirsOut"}}) {
        SCOPED_TRACE(e.graph);
        auto g = RenderGraph::load(kSource + "/" + e.graph);
        auto cg = g->compile(32, 16);
        int src = resourceIndex(cg, e.prevReservoirs);
        int hist = resourceIndex(cg, "temporal.prevReservoirs");
        EXPECT_EQ(cg.resources[hist].name, std::string(e.prevReservoirs) + "@prev");
        EXPECT_EQ(cg.resources[hist].historyOf, src);
        EXPECT_TRUE(cg.resources[hist].persistent);
        EXPECT_EQ(cg.resources[hist].bytes, cg.resources[src].bytes);
        expectLivesToFrameEnd(cg, src);
        expectUnaliased(cg, hist);
        int prim = resourceIndex(cg, "temporal.prevPrimary");
        EXPECT_EQ(cg.resources[prim].historyOf, resourceIndex(cg, "initial.primary"));
        // Temporal still runs after initial and before shade.
        auto order = orderNames(*g, cg);
        auto pos = [&](const std::string& n) {
            return std::find(order.begin(), order.end(), n) - order.begin();
        };
        EXPECT_LT(pos("initial"), pos("temporal"));
        EXPECT_LT(pos("temporal"), pos("shade"));
    }
}

}  // namespace
