#pragma once
// Automatic layout of a render graph for the inspector's graph view: passes become boxes in
// columns by topological depth (left to right), ports become pins on the box edges. Pure
// geometry, no window: unit-tested in tests/unit/test_inspector_layout.cpp.
#include <string>
#include <vector>

#include "core/graph/RenderGraph.h"

namespace loom::inspector {

struct LayoutStyle {
    float nodeWidth = 136.0f;  // minimum; wider when titles or port labels need it
    float charWidth = 7.0f;    // of the UI font (ImGui's default ProggyClean)
    float labelGap = 28.0f;    // between an input label and an output label on one row
    float headerHeight = 22.0f;
    float pinSpacing = 18.0f;
    float padding = 6.0f;     // below the last pin
    float columnGap = 40.0f;  // room for edges between columns
    float rowGap = 24.0f;
    float margin = 16.0f;
};

struct LayoutPin {
    std::string port;
    bool isInput = true;
    ResourceKind kind = ResourceKind::Texture;
    bool optional = false;
    bool graphOutput = false;  // marked in the graph's "outputs"
    float x = 0.0f, y = 0.0f;  // centre, in layout space
};

struct LayoutNode {
    std::string pass, type;
    int column = 0, row = 0;
    float x = 0.0f, y = 0.0f, width = 0.0f, height = 0.0f;  // top-left and size
    std::vector<LayoutPin> inputs, outputs;
    const LayoutPin* findPin(const std::string& port, bool isInput) const;
};

struct LayoutEdge {
    int src = -1, dst = -1;        // node indices
    int srcPin = -1, dstPin = -1;  // indices into outputs / inputs; -1 = execution-only edge
    bool backEdge = false;         // goes right to left (feedback into an earlier column)
};

struct GraphLayout {
    std::vector<LayoutNode> nodes;  // in the graph's declaration order
    std::vector<LayoutEdge> edges;
    float width = 0.0f, height = 0.0f;            // bounding size including margins
    int findNode(const std::string& pass) const;  // -1 when absent
};

// Columns: longest path from the sources over the edges, with edges that close a cycle
// (temporal feedback) left out. Rows: declaration order, then ordered by the mean row of
// each node's predecessors so edges cross less.
GraphLayout layoutGraph(const RenderGraph& graph, const LayoutStyle& style = {});

}  // namespace loom::inspector
