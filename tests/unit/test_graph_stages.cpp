// The compile stages one by one, without a GPU (core/graph/CompileStages.h): models are built
// from PassReflection declarations directly, so in-place outputs and scratch resources need no
// pass type. Covers cull, order (feedback edges exempt, in-place ordering edges and their
// errors), createResources (in-place mapping and checks, scratch), feedback (history copies and
// when they run) and alias (never overlapping lifetimes, sharing when disjoint).
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/graph/CompileStages.h"

namespace {

using loom::CompiledGraph;
using loom::GraphError;
using loom::PassReflection;
using loom::ResourceKind;
namespace stages = loom::stages;
namespace gpu = loom::gpu;

using Declare = std::function<void(PassReflection&)>;

struct Builder {
    stages::GraphModel m;
    Builder() {
        m.where = "test.json";
        m.edgesWhere = "test.json:/edges";
        m.outputsWhere = "test.json:/outputs";
    }
    Builder& pass(const std::string& name, const Declare& declare) {
        PassReflection r;
        declare(r);
        m.nodes.push_back({name, "Test", r, "test.json:" + name});
        return *this;
    }
    Builder& edge(const std::string& from, const std::string& to) {
        auto split = [](const std::string& s) {
            auto d = s.find('.');
            return d == std::string::npos ? std::pair{s, std::string()}
                                          : std::pair{s.substr(0, d), s.substr(d + 1)};
        };
        auto [s, sp] = split(from);
        auto [d, dp] = split(to);
        m.edges.push_back({s, sp, d, dp, "edge " + from + " -> " + to});
        return *this;
    }
    Builder& output(const std::string& port) {
        m.outputs.push_back(port);
        m.outputWhere.push_back("test.json:/outputs/" + port);
        return *this;
    }
};

// Declarations used below: rgba32f frame-size texture ports.
Declare source() {
    return [](PassReflection& r) { r.outputTexture("out"); };
}
Declare filter() {
    return [](PassReflection& r) {
        r.inputTexture("in");
        r.outputTexture("out");
    };
}
// Writes its input in place: output "out" is input "in".
Declare inPlace(bool optionalInput = false) {
    return [=](PassReflection& r) {
        r.inputTexture("in").optional(optionalInput);
        r.outputTexture("out").inPlaceOf("in");
    };
}

struct Compiled {
    stages::CullResult cull;
    stages::OrderResult order;
    stages::ResourcePlan plan;
    stages::AliasResult alias;
};
Compiled run(const stages::GraphModel& m, uint32_t w = 8, uint32_t h = 8, bool aliasing = true) {
    Compiled c;
    stages::validate(m);
    c.cull = stages::cull(m);
    c.order = stages::order(m, c.cull);
    c.plan = stages::createResources(m, c.cull, c.order, w, h);
    c.plan = stages::feedback(m, c.cull, c.order, c.plan);
    c.alias = stages::alias(c.plan.resources, aliasing);
    return c;
}

std::vector<std::string> names(const stages::GraphModel& m, const std::vector<int>& order) {
    std::vector<std::string> n;
    for (int i : order) n.push_back(m.nodes[i].name);
    return n;
}

std::string errorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const GraphError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no GraphError";
    return "";
}

const CompiledGraph::Resource& res(const stages::ResourcePlan& p, const std::string& key) {
    return p.resources[p.portResource.at(key)];
}

// The aliasing invariant: resources that share memory never have overlapping lifetimes.
void expectNoOverlap(const std::vector<CompiledGraph::Resource>& rs, const stages::AliasResult& a) {
    for (size_t i = 0; i < rs.size(); ++i)
        for (size_t j = i + 1; j < rs.size(); ++j) {
            if (a.physical[i] != a.physical[j]) continue;
            bool disjoint = rs[i].lastUse < rs[j].firstUse || rs[j].lastUse < rs[i].firstUse;
            EXPECT_TRUE(disjoint) << rs[i].name << " [" << rs[i].firstUse << "," << rs[i].lastUse
                                  << "] shares memory with " << rs[j].name << " [" << rs[j].firstUse
                                  << "," << rs[j].lastUse << "]";
            EXPECT_FALSE(rs[i].persistent || rs[j].persistent || rs[i].graphOutput ||
                         rs[j].graphOutput);
        }
}

// ---------------------------------------------------------------------------------------------
// validate

TEST(GraphStages, ValidateRejectsBadInPlaceDeclarations) {
    auto decl = [](const Declare& d) {
        Builder b;
        b.pass("src", source()).pass("w", d).edge("src.out", "w.in").output("w.out");
        return errorOf([&] { stages::validate(b.m); });
    };
    std::string e = decl([](PassReflection& r) {
        r.inputTexture("in");
        r.outputTexture("out").inPlaceOf("nope");
    });
    EXPECT_NE(e.find("test.json:w"), std::string::npos) << e;
    EXPECT_NE(e.find("output 'out' is declared in place of 'nope'"), std::string::npos) << e;
    EXPECT_NE(e.find("inputs: in"), std::string::npos) << e;

    e = decl([](PassReflection& r) {
        r.inputTexture("in");
        r.outputBuffer("out").inPlaceOf("in");
    });
    EXPECT_NE(e.find("in-place output 'out' is a buffer but its input 'in' is a texture"),
              std::string::npos)
        << e;

    e = decl([](PassReflection& r) {
        r.inputTexture("in", gpu::Format::RGBA32F);
        r.outputTexture("out", gpu::Format::R32F).inPlaceOf("in");
    });
    EXPECT_NE(e.find("in-place output 'out' is r32f but its input 'in' is rgba32f"),
              std::string::npos)
        << e;

    e = decl([](PassReflection& r) {
        r.inputTexture("in").previousFrame();
        r.outputTexture("out").inPlaceOf("in");
    });
    EXPECT_NE(e.find("cannot be in place of 'in': a previous-frame input"), std::string::npos) << e;

    e = decl([](PassReflection& r) {
        r.inputTexture("in");
        r.outputTexture("out").inPlaceOf("in");
        r.outputTexture("out2").inPlaceOf("in");
    });
    EXPECT_NE(e.find("outputs 'out' and 'out2' are both in place of input 'in'"), std::string::npos)
        << e;
}

TEST(GraphStages, ValidateStillRejectsDataCycles) {
    Builder b;
    b.pass("a", filter()).pass("b", filter()).edge("a.out", "b.in").edge("b.out", "a.in");
    b.output("b.out");
    std::string e = errorOf([&] { stages::validate(b.m); });
    EXPECT_NE(e.find("graph has a cycle: b -> a -> b"), std::string::npos) << e;
}

// ---------------------------------------------------------------------------------------------
// cull

TEST(GraphStages, CullRemovesNodesNotReachingAMarkedOutput) {
    Builder b;
    b.pass("a", source()).pass("b", filter()).pass("side", filter()).pass("alone", source());
    b.edge("a.out", "b.in").edge("a.out", "side.in").output("b.out");
    auto c = stages::cull(b.m);
    EXPECT_EQ(c.keep, (std::vector<bool>{true, true, false, false}));
    EXPECT_EQ(c.culled, (std::vector<std::string>{"side", "alone"}));
}

TEST(GraphStages, CullRequiresInPlaceInputsUnlessOptional) {
    Builder b;
    b.pass("w", inPlace()).output("w.out");
    std::string e = errorOf([&] { stages::cull(b.m); });
    EXPECT_NE(e.find("pass 'w' (Test): required input 'in' is not connected (output 'out' is "
                     "written in place of it"),
              std::string::npos)
        << e;

    // Optional and unconnected: the output gets a resource of its own.
    Builder o;
    o.pass("w", inPlace(true)).output("w.out");
    auto c = run(o.m);
    ASSERT_EQ(c.plan.resources.size(), 1u);
    EXPECT_EQ(res(c.plan, "w.out").name, "w.out");
    EXPECT_TRUE(res(c.plan, "w.out").inPlaceWriters.empty());
}

// ---------------------------------------------------------------------------------------------
// order

TEST(GraphStages, OrderIsTopologicalWithFeedbackEdgesExempt) {
    // b feeds a's previous-frame input: no constraint, so a (a source this frame) runs first.
    Builder b;
    b.pass("b", filter()).pass("a", [](PassReflection& r) {
        r.inputTexture("prev").previousFrame();
        r.outputTexture("out");
    });
    b.edge("a.out", "b.in").edge("b.out", "a.prev").output("b.out");
    auto c = stages::cull(b.m);
    auto o = stages::order(b.m, c);
    EXPECT_EQ(names(b.m, o.order), (std::vector<std::string>{"a", "b"}));
    EXPECT_EQ(o.position, (std::vector<int>{1, 0}));
    EXPECT_TRUE(o.inPlaceEdges.empty());
}

TEST(GraphStages, OrderRunsOtherReadersBeforeTheInPlaceWriter) {
    // w is declared before the reader r; without the in-place edge w would run first and r
    // would read a.out after w overwrote it.
    Builder b;
    b.pass("a", source()).pass("w", inPlace()).pass("r", filter());
    b.edge("a.out", "w.in").edge("a.out", "r.in").output("w.out").output("r.out");
    auto c = stages::cull(b.m);
    auto o = stages::order(b.m, c);
    EXPECT_EQ(names(b.m, o.order), (std::vector<std::string>{"a", "r", "w"}));
    ASSERT_EQ(o.inPlaceEdges.size(), 1u);
    EXPECT_EQ(o.inPlaceEdges[0], (stages::OrderingEdge{"r", "w", "a.out"}));
}

TEST(GraphStages, OrderChainsInPlaceWritersThroughTheirOutputs) {
    // a -> w1 (in place) -> w2 (in place); r1 reads a.out, r2 reads w1.out: each reader runs
    // before the next writer of the value it reads.
    Builder b;
    b.pass("w2", inPlace()).pass("w1", inPlace()).pass("r2", filter()).pass("r1", filter());
    b.pass("a", source());
    b.edge("a.out", "w1.in").edge("w1.out", "w2.in").edge("a.out", "r1.in");
    b.edge("w1.out", "r2.in").output("w2.out").output("r1.out").output("r2.out");
    auto o = stages::order(b.m, stages::cull(b.m));
    auto n = names(b.m, o.order);
    auto at = [&](const char* x) { return std::find(n.begin(), n.end(), x) - n.begin(); };
    EXPECT_LT(at("a"), at("r1"));
    EXPECT_LT(at("r1"), at("w1"));
    EXPECT_LT(at("w1"), at("r2"));
    EXPECT_LT(at("r2"), at("w2"));
    EXPECT_EQ(o.inPlaceEdges.size(), 2u);
}

TEST(GraphStages, OrderRejectsTwoInPlaceWritersOfOneValue) {
    Builder b;
    b.pass("a", source()).pass("w1", inPlace()).pass("w2", inPlace());
    b.edge("a.out", "w1.in").edge("a.out", "w2.in").output("w1.out").output("w2.out");
    std::string e = errorOf([&] { stages::order(b.m, stages::cull(b.m)); });
    EXPECT_NE(e.find("passes 'w1' (output 'out') and 'w2' (output 'out') both write a.out in "
                     "place"),
              std::string::npos)
        << e;
}

TEST(GraphStages, OrderRejectsAnInPlaceWriteThatCannotComeLast) {
    // r reads a.out (so must run before w overwrites it) and w.side (so must run after w).
    Builder b;
    b.pass("a", source())
        .pass("w",
              [](PassReflection& r) {
                  r.inputTexture("in");
                  r.outputTexture("out").inPlaceOf("in");
                  r.outputTexture("side");
              })
        .pass("r", [](PassReflection& r) {
            r.inputTexture("x");
            r.inputTexture("y");
            r.outputTexture("out");
        });
    b.edge("a.out", "w.in").edge("a.out", "r.x").edge("w.side", "r.y");
    b.output("r.out").output("w.out");
    stages::validate(b.m);  // no data cycle
    std::string e = errorOf([&] { stages::order(b.m, stages::cull(b.m)); });
    EXPECT_NE(e.find("'w' writes a.out in place, so 'r', which reads a.out, must run before it"),
              std::string::npos)
        << e;
    EXPECT_NE(e.find("r -> w -> r"), std::string::npos) << e;
}

// ---------------------------------------------------------------------------------------------
// createResources

TEST(GraphStages, InPlaceOutputIsItsInputsResource) {
    Builder b;
    b.pass("a", source()).pass("w", inPlace()).pass("r", filter()).pass("late", filter());
    b.edge("a.out", "w.in").edge("w.out", "r.in").edge("r.out", "late.in").output("late.out");
    auto c = run(b.m);
    int ri = c.plan.portResource.at("a.out");
    EXPECT_EQ(c.plan.portResource.at("w.in"), ri);
    EXPECT_EQ(c.plan.portResource.at("w.out"), ri);
    EXPECT_EQ(c.plan.portResource.at("r.in"), ri);
    const auto& r = c.plan.resources[ri];
    EXPECT_EQ(r.name, "a.out");
    EXPECT_EQ(r.inPlaceWriters, (std::vector<std::string>{"w.out"}));
    // Lives from a (0) to w.out's reader r (2).
    EXPECT_EQ(r.firstUse, 0);
    EXPECT_EQ(r.lastUse, 2);
    // Three resources: a.out (with w.out), r.out, late.out.
    EXPECT_EQ(c.plan.resources.size(), 3u);
    expectNoOverlap(c.plan.resources, c.alias);
}

TEST(GraphStages, InPlaceOutputMustMatchItsInputsResource) {
    auto errorFor = [](const Declare& writer) {
        Builder b;
        b.pass("a", source()).pass("w", writer).edge("a.out", "w.in").output("w.out");
        return errorOf([&] { run(b.m); });
    };
    std::string e = errorFor([](PassReflection& r) {
        r.inputTexture("in");  // any format: only the resource can tell
        r.outputTexture("out", gpu::Format::RGBA16F).inPlaceOf("in");
    });
    EXPECT_NE(e.find("test.json:w: pass 'w' (Test): in-place output 'out' is a rgba16f texture "
                     "8x8 but input 'in' is connected to a.out, a rgba32f texture 8x8"),
              std::string::npos)
        << e;
    e = errorFor([](PassReflection& r) {
        r.inputTexture("in");
        r.outputTexture("out").scale(0.5f).inPlaceOf("in");
    });
    EXPECT_NE(e.find("'out' is a rgba32f texture 4x4 but input 'in' is connected to a.out, a "
                     "rgba32f texture 8x8"),
              std::string::npos)
        << e;

    Builder b;
    b.pass("a", [](PassReflection& r) { r.outputBuffer("out").bytesPerPixel(16); });
    b.pass("w", [](PassReflection& r) {
        r.inputBuffer("in");
        r.outputBuffer("out").bytes(64).inPlaceOf("in");
    });
    b.edge("a.out", "w.in").output("w.out");
    e = errorOf([&] { run(b.m); });
    EXPECT_NE(e.find("'out' is a buffer of 64 bytes but input 'in' is connected to a.out, a "
                     "buffer of 1024 bytes"),
              std::string::npos)
        << e;
}

TEST(GraphStages, InPlaceWriteOfAMarkedOutputIsRejected) {
    Builder b;
    b.pass("a", source()).pass("w", inPlace()).edge("a.out", "w.in");
    b.output("a.out").output("w.out");
    std::string e = errorOf([&] { run(b.m); });
    EXPECT_NE(e.find("output 'out' overwrites a.out in place, but a.out is a marked graph output"),
              std::string::npos)
        << e;
}

TEST(GraphStages, InPlaceOutputMarkedAsGraphOutputKeepsTheResourceAlive) {
    Builder b;
    b.pass("a", source()).pass("w", inPlace()).pass("r", filter());
    b.edge("a.out", "w.in").edge("a.out", "r.in").output("w.out").output("r.out");
    auto c = run(b.m);
    const auto& r = res(c.plan, "w.out");
    EXPECT_TRUE(r.graphOutput);
    EXPECT_EQ(r.lastUse, 3);
}

TEST(GraphStages, ScratchLivesOnlyDuringItsPass) {
    Builder b;
    b.pass("a", source())
        .pass("s",
              [](PassReflection& r) {
                  r.inputTexture("in");
                  r.outputTexture("out");
                  r.scratchBuffer("tmp").bytesPerPixel(12, 4);
                  r.scratchTexture("half", gpu::Format::R32F).scale(0.5f);
              })
        .pass("z", filter());
    b.edge("a.out", "s.in").edge("s.out", "z.in").output("z.out");
    auto c = run(b.m, 16, 8);
    const auto& tmp = res(c.plan, "s.tmp");
    EXPECT_EQ(tmp.name, "s.tmp");
    EXPECT_TRUE(tmp.scratch);
    EXPECT_FALSE(tmp.persistent);
    EXPECT_EQ(tmp.kind, ResourceKind::Buffer);
    EXPECT_EQ(tmp.bytes, 12u * 16 * 8 + 4);
    EXPECT_EQ(tmp.firstUse, 1);
    EXPECT_EQ(tmp.lastUse, 1);
    const auto& half = res(c.plan, "s.half");
    EXPECT_EQ(half.format, gpu::Format::R32F);
    EXPECT_EQ(half.width, 8u);
    EXPECT_EQ(half.height, 4u);
    EXPECT_EQ(half.firstUse, 1);
    EXPECT_EQ(half.lastUse, 1);
}

TEST(GraphStages, ScratchAliasesDisjointTransientsOnly) {
    // a.out [0,1] ends before c runs (2): c's scratch (same description) reuses its memory,
    // while b.out [1,2] is still read by c. c.out (r32f, so it cannot take a.out's memory
    // first) is written by c.
    Builder b;
    b.pass("a", source())
        .pass("b", filter())
        .pass("c",
              [](PassReflection& r) {
                  r.inputTexture("in");
                  r.outputTexture("out", gpu::Format::R32F);
                  r.scratchTexture("tmp");
              })
        .pass("d", filter());
    b.edge("a.out", "b.in").edge("b.out", "c.in").edge("c.out", "d.in").output("d.out");
    auto c = run(b.m);
    auto phys = [&](const std::string& k) { return c.alias.physical[c.plan.portResource.at(k)]; };
    EXPECT_EQ(phys("c.tmp"), phys("a.out"));
    EXPECT_NE(phys("c.tmp"), phys("b.out"));
    EXPECT_NE(phys("c.tmp"), phys("c.out"));
    expectNoOverlap(c.plan.resources, c.alias);
    // Aliasing off: every resource has its own memory.
    auto off = stages::alias(c.plan.resources, false);
    EXPECT_EQ(off.physicalCount, int(c.plan.resources.size()));
}

// ---------------------------------------------------------------------------------------------
// feedback

TEST(GraphStages, FeedbackCreatesHistoryForPreviousFrameInputs) {
    Builder b;
    b.pass("a", source())
        .pass("t",
              [](PassReflection& r) {
                  r.inputTexture("in");
                  r.inputTexture("prev").previousFrame();
                  r.outputTexture("out");
              })
        .edge("a.out", "t.in")
        .edge("t.out", "t.prev")
        .output("t.out");
    auto m = b.m;
    stages::validate(m);
    auto cull = stages::cull(m);
    auto order = stages::order(m, cull);
    auto plan = stages::createResources(m, cull, order, 8, 8);
    EXPECT_EQ(plan.portResource.count("t.prev"), 0u);  // stage 5's job
    plan = stages::feedback(m, cull, order, plan);
    const auto& h = res(plan, "t.prev");
    EXPECT_EQ(h.name, "t.out@prev");
    EXPECT_TRUE(h.persistent);
    EXPECT_EQ(h.historyOf, plan.portResource.at("t.out"));
    EXPECT_EQ(h.historyCopyAt, 2);  // end of the frame
    EXPECT_EQ(res(plan, "t.out").lastUse, 2);
}

TEST(GraphStages, HistoryOfAValueOverwrittenInPlaceIsCopiedBeforeTheWrite) {
    // h1 reads a.out of the previous frame and w overwrites a.out in place this frame: h1 is
    // ordered before w (although declared after it), and the copy into a.out@prev runs after
    // h1 read the old copy and before w writes, not at the end of the frame (it would hold
    // w's result). The history of w.out (same memory) is copied at the end.
    Builder b;
    b.pass("a", source())
        .pass("w", inPlace())
        .pass("h1",
              [](PassReflection& r) {
                  r.inputTexture("prev").previousFrame();
                  r.outputTexture("out");
              })
        .pass("h2", [](PassReflection& r) {
            r.inputTexture("cur");
            r.inputTexture("prevW").previousFrame();
            r.outputTexture("out");
        });
    b.edge("a.out", "w.in").edge("a.out", "h1.prev").edge("w.out", "h2.cur");
    b.edge("w.out", "h2.prevW").output("h1.out").output("h2.out");
    auto c = run(b.m);
    EXPECT_EQ(names(b.m, c.order.order), (std::vector<std::string>{"a", "h1", "w", "h2"}));
    ASSERT_EQ(c.order.inPlaceEdges.size(), 1u);
    EXPECT_EQ(c.order.inPlaceEdges[0], (stages::OrderingEdge{"h1", "w", "a.out"}));
    EXPECT_TRUE(c.order.inPlaceEdges[0].previousFrame);
    const auto& ha = res(c.plan, "h1.prev");
    EXPECT_EQ(ha.name, "a.out@prev");
    EXPECT_EQ(ha.historyCopyAt, 1);  // after h1, before w
    const auto& hw = res(c.plan, "h2.prevW");
    EXPECT_EQ(hw.name, "w.out@prev");
    EXPECT_EQ(hw.historyCopyAt, 4);         // end of the frame
    EXPECT_EQ(ha.historyOf, hw.historyOf);  // one resource, two values
    EXPECT_EQ(c.plan.resources[ha.historyOf].lastUse, 4);
    expectNoOverlap(c.plan.resources, c.alias);
}

TEST(GraphStages, PreviousFrameReadsThatCannotPrecedeTheInPlaceWriteAreRejected) {
    // The writer itself reads the previous frame of the value it overwrites.
    Builder b;
    b.pass("a", source()).pass("w", [](PassReflection& r) {
        r.inputTexture("in");
        r.inputTexture("prev").previousFrame();
        r.outputTexture("out").inPlaceOf("in");
    });
    b.edge("a.out", "w.in").edge("a.out", "w.prev").output("w.out");
    std::string e = errorOf([&] { run(b.m); });
    EXPECT_NE(e.find("pass 'w' (Test): input 'prev' reads the previous frame of a.out, which the "
                     "pass also writes in place (output 'out')"),
              std::string::npos)
        << e;

    // A previous-frame reader downstream of the writer.
    Builder d;
    d.pass("a", source()).pass("w", inPlace()).pass("h", [](PassReflection& r) {
        r.inputTexture("cur");
        r.inputTexture("prev").previousFrame();
        r.outputTexture("out");
    });
    d.edge("a.out", "w.in").edge("w.out", "h.cur").edge("a.out", "h.prev").output("h.out");
    e = errorOf([&] { run(d.m); });
    EXPECT_NE(e.find("'w' writes a.out in place, so 'h', which reads a.out of the previous "
                     "frame, must run before it"),
              std::string::npos)
        << e;
}

// ---------------------------------------------------------------------------------------------
// alias

CompiledGraph::Resource texture(const std::string& name, int first, int last) {
    CompiledGraph::Resource r;
    r.name = name;
    r.width = r.height = 8;
    r.firstUse = first;
    r.lastUse = last;
    return r;
}

TEST(GraphStages, AliasSharesDisjointAndSeparatesOverlapping) {
    std::vector<CompiledGraph::Resource> rs{texture("a", 0, 1), texture("b", 1, 2),
                                            texture("c", 2, 3), texture("d", 3, 3)};
    auto a = stages::alias(rs, true);
    EXPECT_EQ(a.physical, (std::vector<int>{0, 1, 0, 1}));
    EXPECT_EQ(a.physicalCount, 2);
    expectNoOverlap(rs, a);

    // Different descriptions, persistent, outputs and history copies never share.
    rs = {texture("a", 0, 0), texture("b", 1, 1), texture("c", 2, 2), texture("d", 3, 3),
          texture("e", 4, 4)};
    rs[1].format = gpu::Format::R32F;
    rs[2].persistent = true;
    rs[3].graphOutput = true;
    rs[4].historyOf = 0;
    a = stages::alias(rs, true);
    EXPECT_EQ(a.physicalCount, 5);
}

TEST(GraphStages, AliasNeverOverlapsInRandomGraphsWithInPlaceAndScratch) {
    // Random DAGs of filters, in-place writers and scratch users: whatever the shape, memory
    // shared by two resources is never live for both.
    std::mt19937 rng(7);
    for (int trial = 0; trial < 200; ++trial) {
        Builder b;
        const int n = 3 + int(rng() % 8);
        b.pass("p0", source());
        std::vector<std::string> values{"p0.out"};
        std::set<std::string> written;  // values already written in place
        for (int i = 1; i < n; ++i) {
            std::string name = "p";  // not "p" + ...: GCC 12 warns falsely (-Wrestrict)
            name += std::to_string(i);
            std::string from = values[rng() % values.size()];
            int kind = int(rng() % 3);
            if (kind == 1 && written.insert(from).second) {
                b.pass(name, inPlace());
            } else if (kind == 2) {
                b.pass(name, [](PassReflection& r) {
                    r.inputTexture("in");
                    r.outputTexture("out");
                    r.scratchTexture("tmp");
                });
            } else {
                b.pass(name, filter());
            }
            b.edge(from, name + ".in");
            values.push_back(name + ".out");
        }
        b.output(values.back());
        Compiled c;
        try {
            c = run(b.m);
        } catch (const GraphError&) {
            continue;  // an unorderable in-place write: rejected, nothing to alias
        }
        expectNoOverlap(c.plan.resources, c.alias);
        if (HasFailure()) return;
    }
}

}  // namespace
