#include "apps/inspector/GraphLayout.h"

#include <algorithm>
#include <functional>
#include <map>

namespace loom::inspector {

const LayoutPin* LayoutNode::findPin(const std::string& port, bool isInput) const {
    for (const auto& p : isInput ? inputs : outputs)
        if (p.port == port) return &p;
    return nullptr;
}

int GraphLayout::findNode(const std::string& pass) const {
    for (size_t i = 0; i < nodes.size(); ++i)
        if (nodes[i].pass == pass) return int(i);
    return -1;
}

namespace {

int pinIndex(const std::vector<LayoutPin>& pins, const std::string& port) {
    for (size_t i = 0; i < pins.size(); ++i)
        if (pins[i].port == port) return int(i);
    return -1;
}

}  // namespace

GraphLayout layoutGraph(const RenderGraph& graph, const LayoutStyle& style) {
    GraphLayout layout;
    const auto& passes = graph.passes();
    const size_t n = passes.size();

    // Nodes and pins from each pass's declaration.
    for (const auto& p : passes) {
        LayoutNode node;
        node.pass = p->name();
        node.type = p->type();
        PassReflection refl;
        try {
            refl = p->reflection();
        } catch (const std::exception&) {
            // A pass whose parameters cannot be reflected still gets a box (no pins).
        }
        for (const auto& port : refl.ports()) {
            LayoutPin pin;
            pin.port = port.name;
            pin.isInput = port.isInput;
            pin.kind = port.kind;
            pin.optional = port.optional;
            std::string key = p->name() + "." + port.name;
            pin.graphOutput =
                !port.isInput && std::find(graph.outputs().begin(), graph.outputs().end(), key) !=
                                     graph.outputs().end();
            (port.isInput ? node.inputs : node.outputs).push_back(pin);
        }
        layout.nodes.push_back(std::move(node));
    }

    // Edges (unknown passes or ports are skipped: the graph validated them already).
    for (const auto& e : graph.edges()) {
        LayoutEdge le;
        le.src = layout.findNode(e.src);
        le.dst = layout.findNode(e.dst);
        if (le.src < 0 || le.dst < 0) continue;
        if (!e.isExecutionOnly()) {
            le.srcPin = pinIndex(layout.nodes[le.src].outputs, e.srcPort);
            le.dstPin = pinIndex(layout.nodes[le.dst].inputs, e.dstPort);
        }
        layout.edges.push_back(le);
    }

    // Break cycles: a DFS in declaration order marks edges into a node on the stack.
    std::vector<std::vector<int>> out(n);
    for (size_t i = 0; i < layout.edges.size(); ++i) out[layout.edges[i].src].push_back(int(i));
    std::vector<int> state(n, 0);  // 0 new, 1 on stack, 2 done
    std::function<void(int)> dfs = [&](int v) {
        state[v] = 1;
        for (int ei : out[v]) {
            int w = layout.edges[ei].dst;
            if (state[w] == 1)
                layout.edges[ei].backEdge = true;
            else if (state[w] == 0)
                dfs(w);
        }
        state[v] = 2;
    };
    for (size_t v = 0; v < n; ++v)
        if (!state[v]) dfs(int(v));

    // Columns: longest path over forward edges (Kahn's order keeps it linear).
    std::vector<int> indeg(n, 0);
    for (const auto& e : layout.edges)
        if (!e.backEdge) ++indeg[e.dst];
    std::vector<int> ready;
    for (size_t v = 0; v < n; ++v)
        if (!indeg[v]) ready.push_back(int(v));
    while (!ready.empty()) {
        // Lowest declaration index first: deterministic.
        auto it = std::min_element(ready.begin(), ready.end());
        int v = *it;
        ready.erase(it);
        for (int ei : out[v]) {
            const auto& e = layout.edges[ei];
            if (e.backEdge) continue;
            layout.nodes[e.dst].column =
                std::max(layout.nodes[e.dst].column, layout.nodes[v].column + 1);
            if (--indeg[e.dst] == 0) ready.push_back(e.dst);
        }
    }
    // Rows: per column, ordered by the mean row of predecessors (declaration order first).
    int columns = 0;
    for (const auto& node : layout.nodes) columns = std::max(columns, node.column + 1);
    std::vector<std::vector<int>> byColumn(columns);
    for (size_t v = 0; v < n; ++v) byColumn[layout.nodes[v].column].push_back(int(v));
    for (int c = 0; c < columns; ++c) {
        auto& col = byColumn[c];
        std::vector<double> key(n, 0.0);
        for (int v : col) {
            double sum = 0.0;
            int count = 0;
            for (const auto& e : layout.edges)
                if (e.dst == v && !e.backEdge && layout.nodes[e.src].column < c) {
                    sum += layout.nodes[e.src].row;
                    ++count;
                }
            key[v] = count ? sum / count : 1e9;  // sources keep declaration order at the end
        }
        if (c > 0)
            std::stable_sort(col.begin(), col.end(), [&](int a, int b) { return key[a] < key[b]; });
        for (size_t r = 0; r < col.size(); ++r) layout.nodes[col[r]].row = int(r);
    }

    // Geometry.
    float x = style.margin;
    float maxBottom = 0.0f;
    for (int c = 0; c < columns; ++c) {
        float y = style.margin;
        // One width per column: the widest title or input+output label row of its nodes.
        float colWidth = style.nodeWidth;
        for (int v : byColumn[c]) {
            const auto& node = layout.nodes[v];
            size_t in = 0, out = 0;
            for (auto& p : node.inputs) in = std::max(in, p.port.size());
            for (auto& p : node.outputs) out = std::max(out, p.port.size());
            size_t title = node.pass.size() + 3 + node.type.size();
            colWidth = std::max({colWidth, float(in + out) * style.charWidth + style.labelGap,
                                 float(title) * style.charWidth + 2 * style.padding});
        }
        for (int v : byColumn[c]) {
            auto& node = layout.nodes[v];
            size_t pins = std::max(node.inputs.size(), node.outputs.size());
            node.x = x;
            node.y = y;
            node.width = colWidth;
            node.height = style.headerHeight + float(std::max<size_t>(pins, 1)) * style.pinSpacing +
                          style.padding;
            for (size_t i = 0; i < node.inputs.size(); ++i) {
                node.inputs[i].x = node.x;
                node.inputs[i].y =
                    node.y + style.headerHeight + (float(i) + 0.5f) * style.pinSpacing;
            }
            for (size_t i = 0; i < node.outputs.size(); ++i) {
                node.outputs[i].x = node.x + node.width;
                node.outputs[i].y =
                    node.y + style.headerHeight + (float(i) + 0.5f) * style.pinSpacing;
            }
            y += node.height + style.rowGap;
            maxBottom = std::max(maxBottom, node.y + node.height);
        }
        x += colWidth + style.columnGap;
    }
    layout.width = columns ? x - style.columnGap + style.margin : 2 * style.margin;
    layout.height = maxBottom + style.margin;
    return layout;
}

}  // namespace loom::inspector
