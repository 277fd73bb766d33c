// The memory report (RenderGraph::memoryReport data, `loom render --timings` table, the
// inspector's Memory tab) and ComputePass's "inPlaceOf" field, without a GPU: graphs of
// JSON-declared ComputePasses are compiled and reported.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "apps/inspector/MemoryTable.h"
#include "core/graph/RenderGraph.h"
#include "tests/support/TestSupport.h"

namespace {

using loom::GraphError;
using loom::MemoryReport;
using loom::RenderGraph;
using loom::ResourceMemory;

// gen -> inc (in place) -> lag, with lag reading inc's previous-frame value too and owning a
// persistent buffer; a -> b -> c -> d (with lag) is a chain whose a.out and c.out alias.
const char* kGraph = R"({"name": "mem", "passes": [
  {"name": "gen", "type": "ComputePass", "params": {"shader": "g.comp",
     "outputs": {"values": {"kind": "buffer", "bytesPerPixel": 4}}}},
  {"name": "inc", "type": "ComputePass", "params": {"shader": "i.comp",
     "inputs": {"data": {"kind": "buffer"}},
     "outputs": {"dataOut": {"kind": "buffer", "bytesPerPixel": 4, "inPlaceOf": "data"}}}},
  {"name": "lag", "type": "ComputePass", "params": {"shader": "l.comp",
     "inputs": {"cur": {"kind": "buffer"}, "prev": {"kind": "buffer", "previousFrame": true}},
     "outputs": {"output": {"format": "rgba32f"}},
     "persistent": {"state": {"kind": "buffer", "bytes": 256}}}},
  {"name": "a", "type": "ComputePass", "params": {"shader": "a.comp",
     "outputs": {"out": {"format": "rgba16f"}}}},
  {"name": "b", "type": "ComputePass", "params": {"shader": "b.comp",
     "inputs": {"in": {}}, "outputs": {"out": {"format": "rgba16f"}}}},
  {"name": "c", "type": "ComputePass", "params": {"shader": "c.comp",
     "inputs": {"in": {}}, "outputs": {"out": {"format": "rgba16f"}}}},
  {"name": "d", "type": "ComputePass", "params": {"shader": "d.comp",
     "inputs": {"in": {}, "x": {}}, "outputs": {"out": {"format": "rgba32f"}}}}],
  "edges": [["gen.values", "inc.data"], ["inc.dataOut", "lag.cur"], ["inc.dataOut", "lag.prev"],
            ["a.out", "b.in"], ["b.out", "c.in"], ["c.out", "d.in"], ["lag.output", "d.x"]],
  "outputs": ["d.out"]})";

const ResourceMemory& find(const MemoryReport& r, const std::string& name) {
    for (auto& m : r.resources)
        if (m.name == name) return m;
    throw std::runtime_error("no resource " + name);
}

TEST(GraphMemory, ReportListsEveryResourceWithLifetimeAndSharing) {
    auto g = RenderGraph::parse(kGraph, "mem.json");
    MemoryReport rep = loom::memoryReport(g->compile(16, 8));

    const auto& values = find(rep, "gen.values");
    EXPECT_EQ(values.kind, loom::ResourceKind::Buffer);
    EXPECT_EQ(values.bytes, 16u * 8 * 4);
    EXPECT_EQ(values.lifetime, ResourceMemory::Lifetime::Transient);
    EXPECT_EQ(values.inPlace, (std::vector<std::string>{"inc.dataOut"}));
    const auto& hist = find(rep, "inc.dataOut@prev");
    EXPECT_EQ(hist.lifetime, ResourceMemory::Lifetime::History);
    EXPECT_EQ(find(rep, "lag#state").lifetime, ResourceMemory::Lifetime::Persistent);
    EXPECT_EQ(find(rep, "lag#state").bytes, 256u);
    const auto& out = find(rep, "d.out");
    EXPECT_EQ(out.lifetime, ResourceMemory::Lifetime::Output);
    EXPECT_EQ(out.format, "rgba32f");
    EXPECT_EQ(out.bytes, 16u * 8 * 16);
    // No resource for inc.dataOut of its own: it is gen.values.
    for (auto& m : rep.resources) EXPECT_NE(m.name, "inc.dataOut");

    // a.out [.. b] and c.out [c .. d] have the same description and disjoint lifetimes.
    const auto& aOut = find(rep, "a.out");
    EXPECT_EQ(aOut.aliasedWith, (std::vector<std::string>{"c.out"}));
    EXPECT_EQ(find(rep, "c.out").aliasedWith, (std::vector<std::string>{"a.out"}));
    EXPECT_EQ(aOut.bytes, 16u * 8 * 8);  // rgba16f
    uint64_t sum = 0;
    for (auto& m : rep.resources) sum += m.bytes;
    EXPECT_EQ(rep.unaliasedBytes, sum);
    EXPECT_EQ(rep.allocatedBytes, sum - aOut.bytes);

    // Without aliasing every resource is allocated on its own.
    g->setAliasing(false);
    MemoryReport off = loom::memoryReport(g->compile(16, 8));
    EXPECT_EQ(off.allocatedBytes, off.unaliasedBytes);
    EXPECT_TRUE(find(off, "a.out").aliasedWith.empty());
}

TEST(GraphMemory, TextTableHasOneRowPerResourceAndTotals) {
    auto g = RenderGraph::parse(kGraph, "mem.json");
    MemoryReport rep = loom::memoryReport(g->compile(16, 8));
    std::string text = loom::formatMemoryReport(rep);
    EXPECT_NE(text.find("resource"), std::string::npos) << text;
    EXPECT_NE(text.find("in place: inc.dataOut"), std::string::npos) << text;
    EXPECT_NE(text.find("aliased: c.out"), std::string::npos) << text;
    EXPECT_NE(text.find("history"), std::string::npos) << text;
    EXPECT_NE(text.find(loom::formatBytes(rep.allocatedBytes) + " allocated, " +
                        loom::formatBytes(rep.unaliasedBytes) + " without aliasing"),
              std::string::npos)
        << text;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), long(rep.resources.size()) + 2);
    EXPECT_EQ(loom::formatBytes(96), "96 B");
    EXPECT_EQ(loom::formatBytes(3 * 1024), "3.0 KiB");
    EXPECT_EQ(loom::formatBytes(5 * 1024 * 1024 + 512 * 1024), "5.5 MiB");
}

TEST(GraphMemory, ReportIsEmptyBeforeTheFirstFrame) {
    auto g = RenderGraph::parse(kGraph, "mem.json");
    EXPECT_TRUE(g->memoryReport().resources.empty());
}

TEST(InspectorMemory, TableRowsMatchTheReportAndMarkTheSelectedPass) {
    auto g = RenderGraph::parse(kGraph, "mem.json");
    MemoryReport rep = loom::memoryReport(g->compile(16, 8));
    auto t = loom::inspector::memoryTable(rep, "lag", true);
    ASSERT_EQ(t.rows.size(), rep.resources.size());
    for (size_t i = 0; i < t.rows.size(); ++i) {
        const auto& row = t.rows[i];
        EXPECT_EQ(row.name, rep.resources[i].name);
        EXPECT_EQ(row.bytes, loom::formatBytes(rep.resources[i].bytes));
        EXPECT_EQ(row.lifetime, loom::lifetimeName(rep.resources[i].lifetime));
        // lag's own resources: its output and its persistent state (not inc.dataOut@prev,
        // which belongs to inc).
        bool own = row.name == "lag.output" || row.name == "lag#state";
        EXPECT_EQ(row.ofSelectedPass, own) << row.name;
    }
    auto row = [&](const std::string& n) {
        for (auto& r : t.rows)
            if (r.name == n) return r;
        throw std::runtime_error("no row " + n);
    };
    EXPECT_EQ(row("d.out").size, "rgba32f 16x8");
    EXPECT_EQ(row("d.out").kind, "texture");
    EXPECT_EQ(row("gen.values").size, "512 B");
    EXPECT_EQ(row("gen.values").shares, "in place: inc.dataOut");
    EXPECT_EQ(row("a.out").shares, "aliased: c.out");
    EXPECT_NE(t.summary.find("allocated"), std::string::npos);
    EXPECT_EQ(t.summary.find("aliasing off"), std::string::npos);
    EXPECT_NE(loom::inspector::memoryTable(rep, "", false).summary.find("aliasing off"),
              std::string::npos);
}

TEST(GraphMemory, ComputePassInPlaceOfIsValidated) {
    auto parse = [](const std::string& inputs, const std::string& outputs) {
        std::string text = R"({"passes": [
          {"name": "src", "type": "ComputePass", "params": {"shader": "s.comp",
             "outputs": {"out": {}}}},
          {"name": "w", "type": "ComputePass", "params": {"shader": "w.comp",
             "inputs": )" + inputs + R"(, "outputs": )" + outputs + R"(}}],
          "edges": [["src.out", "w.in"]], "outputs": ["w.out"]})";
        try {
            RenderGraph::parse(text, "inplace.json")->compile(8, 8);
        } catch (const GraphError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_EQ(parse(R"({"in": {}})", R"({"out": {"inPlaceOf": "in"}})"), "");
    std::string e = parse(R"({"in": {"inPlaceOf": "x"}})", R"({"out": {}})");
    EXPECT_NE(e.find("input 'in': 'inPlaceOf' applies to outputs only"), std::string::npos) << e;
    e = parse(R"({"in": {}})", R"({"out": {"inPlaceOf": 3}})");
    EXPECT_NE(e.find("'inPlaceOf' must be a string"), std::string::npos) << e;
    e = parse(R"({"in": {}})", R"({"out": {"inPlaceOf": "nope"}})");
    EXPECT_NE(e.find("inplace.json"), std::string::npos) << e;
    EXPECT_NE(e.find("pass 'w' (ComputePass): output 'out' is declared in place of 'nope'"),
              std::string::npos)
        << e;
    e = parse(R"({"in": {}})", R"({"out": {"inPlaceOf": "in", "format": "r32f"}})");
    EXPECT_NE(e.find("in-place output 'out' is a r32f texture 8x8 but input 'in' is connected "
                     "to src.out, a rgba32f texture 8x8"),
              std::string::npos)
        << e;
}

// ---------------------------------------------------------------------------------------------
// CLI: `loom render --timings` prints the report after the timing table; a bad in-place graph
// exits 2 with one message naming file, node and ports.

struct CommandResult {
    int exitCode = -1;
    std::string out, err;
};

CommandResult runLoom(const std::string& args) {
    loom::test::TempDir tmp("loom-cli-memory");
    std::string cmd = std::string("cd '") + LOOM_SOURCE_DIR + "' && '" + LOOM_BINARY + "' " +
                      args + " >'" + (tmp / "out") + "' 2>'" + (tmp / "err") + "'";
    int status = std::system(cmd.c_str());
    CommandResult r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = loom::test::readFile(tmp / "out");
    r.err = loom::test::readFile(tmp / "err");
    return r;
}

TEST(LoomCli, TimingsPrintTheMemoryReport) {
    loom::test::TempDir tmp("loom-cli-memory-out");
    auto r = runLoom("render graphs/hello_compute.json --width 8 --height 8 --frames 2 --timings "
                     "--quiet --out '" +
                     (tmp / "x.png") + "'");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    size_t timing = r.out.find("total (GPU)"), table = r.out.find("resource");
    ASSERT_NE(timing, std::string::npos) << r.out;
    ASSERT_NE(table, std::string::npos) << r.out;
    EXPECT_LT(timing, table);
    EXPECT_NE(r.out.find("accum#mean"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("persistent"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("without aliasing"), std::string::npos) << r.out;
}

TEST(LoomCli, BadInPlaceGraphExitsTwoNamingNodeAndPorts) {
    loom::test::TempDir tmp("loom-cli-inplace");
    loom::test::writeFile(tmp / "bad.json", R"({"passes": [
  {"name": "src", "type": "ComputePass", "params": {"shader": "s.comp",
     "outputs": {"out": {"format": "rgba32f"}}}},
  {"name": "w", "type": "ComputePass", "params": {"shader": "w.comp",
     "inputs": {"in": {}}, "outputs": {"out": {"format": "r32f", "inPlaceOf": "in"}}}}],
  "edges": [["src.out", "w.in"]], "outputs": ["w.out"]})");
    auto r = runLoom("validate '" + (tmp / "bad.json") + "'");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("bad.json"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("pass 'w' (ComputePass): in-place output 'out' is a r32f texture"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

}  // namespace
