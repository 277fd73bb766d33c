#pragma once
// The stages of RenderGraph::compile() as functions of plain data, in the order they run:
//   validate -> cull -> order -> createResources -> feedback -> alias
// Each takes what the earlier stages produced and returns a plain structure, so every stage is
// unit-tested without a GPU (tests/unit/test_graph_stages.cpp). Stages throw GraphError with
// the file/line, node and ports of the problem.
#include <map>
#include <string>
#include <vector>

#include "core/graph/Pass.h"
#include "core/graph/RenderGraph.h"

namespace loom::stages {

// What the stages see of a graph: its passes' declarations, edges and marked outputs, with the
// source locations that messages cite.
struct GraphModel {
    struct Node {
        std::string name, type;
        PassReflection refl;
        std::string where;  // "file:line:col" of the pass (or the graph's name)
    };
    std::vector<Node> nodes;  // declaration order
    std::vector<GraphEdge> edges;
    std::vector<std::string> outputs;      // "node.port"
    std::vector<std::string> outputWhere;  // per output
    std::string where;                     // the graph as a whole
    std::string edgesWhere, outputsWhere;

    int find(const std::string& name) const;  // -1 when absent
    // An edge into a previous-frame input: temporal feedback, exempt from ordering and cycles.
    bool isFeedback(const GraphEdge& e) const;
    // The ordinary (non-feedback) data edge into input `node.port`; nullptr when unconnected.
    const GraphEdge* inputEdge(const std::string& node, const std::string& port) const;
};

// Stage 1: edges name existing ports of matching kind and format, each input has at most one
// edge, outputs exist, in-place declarations are sound, and there is no cycle.
void validate(const GraphModel& g);

// Stage 2: passes that reach no marked output are culled; kept passes must have their
// required inputs connected.
struct CullResult {
    std::vector<bool> keep;           // per node
    std::vector<std::string> culled;  // declaration order
};
CullResult cull(const GraphModel& g);

// Stage 3: topological order of the kept passes (ties keep declaration order). Feedback edges
// impose no order, except that in-place writes add edges so that every other reader of the
// overwritten value runs first, previous-frame readers included (its history copy is
// refreshed between them and the write).
struct OrderingEdge {
    std::string before, after;   // pass names
    std::string resource;        // "node.port" whose value `after` overwrites in place
    bool previousFrame = false;  // `before` reads the resource's previous-frame history copy
    bool operator==(const OrderingEdge& o) const {
        return before == o.before && after == o.after && resource == o.resource;
    }
};
struct OrderResult {
    std::vector<int> order;     // node indices in execution order
    std::vector<int> position;  // per node: index in `order`, -1 when culled
    std::vector<OrderingEdge> inPlaceEdges;
};
OrderResult order(const GraphModel& g, const CullResult& c);

// Stage 4: one logical resource per produced port that is consumed, marked or not optional;
// in-place outputs map onto the resource of their input; persistent and scratch resources.
// Lifetimes are positions in the order (scratch: its pass only). Throws when an in-place
// output does not match its input's resource.
struct ResourcePlan {
    std::vector<CompiledGraph::Resource> resources;
    std::map<std::string, int> portResource;  // as CompiledGraph::portResource
};
ResourcePlan createResources(const GraphModel& g, const CullResult& c, const OrderResult& o,
                             uint32_t width, uint32_t height);

// Stage 5: previous-frame inputs read a persistent "src.port@prev" history copy (one per
// produced port). The copy runs at the end of the frame or, when a later pass overwrites that
// value in place, after its producer and its previous-frame readers (before the write); the
// source lives until the copy.
ResourcePlan feedback(const GraphModel& g, const CullResult& c, const OrderResult& o,
                      ResourcePlan plan);

// Stage 6: transient resources (scratch included) with identical descriptions and disjoint
// lifetimes share physical memory; persistent, history and graph-output resources never do.
struct AliasResult {
    std::vector<int> physical;  // per resource
    int physicalCount = 0;
};
AliasResult alias(const std::vector<CompiledGraph::Resource>& resources, bool enabled);

// Texture/buffer size from a size rule at a frame size (shared by stages and tests).
void applySize(CompiledGraph::Resource& r, const SizeRule& s, uint32_t width, uint32_t height);

}  // namespace loom::stages
