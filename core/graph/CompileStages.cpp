#include "core/graph/CompileStages.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/util/Log.h"

namespace loom::stages {

namespace {

std::string joinNames(const std::vector<std::string>& names, const char* sep = ", ") {
    std::string out;
    for (auto& n : names) out += (out.empty() ? "" : sep) + n;
    return out;
}

std::string portList(const PassReflection& r, bool inputs) {
    std::vector<std::string> names;
    for (auto& p : r.ports())
        if (p.isInput == inputs) names.push_back(p.name);
    return names.empty() ? "(none)" : joinNames(names);
}

const char* kindName(ResourceKind k) {
    return k == ResourceKind::Texture ? "texture" : "buffer";
}

std::string describe(const CompiledGraph::Resource& r) {
    if (r.kind == ResourceKind::Texture)
        return fmt::format("{} texture {}x{}", gpu::formatName(r.format), r.width, r.height);
    return fmt::format("buffer of {} bytes", r.bytes);
}

// A cycle among `remaining` nodes of a graph given by predecessor lists, as names in edge
// order with the first repeated at the end. Every remaining node has a remaining predecessor
// (Kahn left it with a positive indegree), so walking predecessors must revisit a node.
std::vector<std::string> findCycle(const GraphModel& g, const std::vector<int>& remaining,
                                   const std::vector<std::vector<int>>& pred) {
    std::set<int> rem(remaining.begin(), remaining.end());
    std::vector<int> path;
    int cur = remaining.front();
    while (std::find(path.begin(), path.end(), cur) == path.end()) {
        path.push_back(cur);
        for (int p : pred[cur])
            if (rem.count(p)) {
                cur = p;
                break;
            }
    }
    auto first = std::find(path.begin(), path.end(), cur);
    std::vector<std::string> cycle;
    for (auto it = first; it != path.end(); ++it) cycle.push_back(g.nodes[*it].name);
    std::reverse(cycle.begin(), cycle.end());  // predecessor order -> edge order
    cycle.push_back(cycle.front());
    return cycle;
}

// The in-place outputs of a pass whose in-place input is connected: {output, input edge}.
std::vector<std::pair<const PortDesc*, const GraphEdge*>> inPlaceWrites(const GraphModel& g,
                                                                        int node) {
    std::vector<std::pair<const PortDesc*, const GraphEdge*>> out;
    for (auto& p : g.nodes[node].refl.ports()) {
        if (p.isInput || p.inPlaceOf.empty()) continue;
        if (const GraphEdge* e = g.inputEdge(g.nodes[node].name, p.inPlaceOf))
            out.push_back({&p, e});
    }
    return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// GraphModel

int GraphModel::find(const std::string& name) const {
    for (size_t i = 0; i < nodes.size(); ++i)
        if (nodes[i].name == name) return int(i);
    return -1;
}

bool GraphModel::isFeedback(const GraphEdge& e) const {
    if (e.isExecutionOnly()) return false;
    int d = find(e.dst);
    if (d < 0) return false;
    const PortDesc* p = nodes[d].refl.findPort(e.dstPort);
    return p && p->isInput && p->previousFrame;
}

const GraphEdge* GraphModel::inputEdge(const std::string& node, const std::string& port) const {
    for (auto& e : edges)
        if (!e.isExecutionOnly() && e.dst == node && e.dstPort == port && !isFeedback(e)) return &e;
    return nullptr;
}

// ---------------------------------------------------------------------------------------------
// Stage 1: validate

void validate(const GraphModel& g) {
    auto nodeNames = [&] {
        std::vector<std::string> n;
        for (auto& x : g.nodes) n.push_back(x.name);
        return joinNames(n);
    };
    auto requireNode = [&](const std::string& node, const std::string& at) {
        if (g.find(node) < 0)
            throw GraphError(at + ": edge refers to unknown pass '" + node +
                             "'; passes: " + nodeNames());
    };

    // In-place declarations: each names an input of the same pass, of the same kind, read in
    // this frame (a previous-frame input is the graph's history copy, refreshed at frame end).
    for (auto& n : g.nodes) {
        std::map<std::string, std::string> writerOf;  // input -> in-place output
        for (auto& o : n.refl.ports()) {
            if (o.isInput || o.inPlaceOf.empty()) continue;
            const PortDesc* in = n.refl.findPort(o.inPlaceOf);
            if (!in || !in->isInput)
                throw GraphError(fmt::format(
                    "{}: pass '{}' ({}): output '{}' is declared in place of '{}', which is not "
                    "an input of the pass; inputs: {}",
                    n.where, n.name, n.type, o.name, o.inPlaceOf, portList(n.refl, true)));
            if (in->kind != o.kind)
                throw GraphError(fmt::format(
                    "{}: pass '{}' ({}): in-place output '{}' is a {} but its input '{}' is a {}",
                    n.where, n.name, n.type, o.name, kindName(o.kind), in->name,
                    kindName(in->kind)));
            if (o.kind == ResourceKind::Texture && in->format && o.format &&
                *in->format != *o.format)
                throw GraphError(fmt::format(
                    "{}: pass '{}' ({}): in-place output '{}' is {} but its input '{}' is {}",
                    n.where, n.name, n.type, o.name, gpu::formatName(*o.format), in->name,
                    gpu::formatName(*in->format)));
            if (in->previousFrame)
                throw GraphError(fmt::format(
                    "{}: pass '{}' ({}): output '{}' cannot be in place of '{}': a previous-frame "
                    "input reads the graph's history copy, which is refreshed at the end of each "
                    "frame; write a new output, or keep the state in a persistent resource",
                    n.where, n.name, n.type, o.name, in->name));
            if (writerOf.count(in->name))
                throw GraphError(fmt::format(
                    "{}: pass '{}' ({}): outputs '{}' and '{}' are both in place of input '{}'",
                    n.where, n.name, n.type, writerOf[in->name], o.name, in->name));
            writerOf[in->name] = o.name;
        }
    }

    std::map<std::string, const GraphEdge*> inputSource;
    for (const auto& e : g.edges) {
        std::string at = e.where.empty() ? g.edgesWhere : e.where;
        requireNode(e.src, at);
        requireNode(e.dst, at);
        if (e.src == e.dst && !g.isFeedback(e))
            throw GraphError(at + ": pass '" + e.src + "' is connected to itself");
        if (e.isExecutionOnly()) continue;
        const auto& sn = g.nodes[g.find(e.src)];
        const auto& dn = g.nodes[g.find(e.dst)];
        const PortDesc* so = sn.refl.findPort(e.srcPort);
        if (!so || so->isInput)
            throw GraphError(fmt::format("{}: pass '{}' ({}) has no output '{}'; outputs: {}", at,
                                         e.src, sn.type, e.srcPort, portList(sn.refl, false)));
        const PortDesc* di = dn.refl.findPort(e.dstPort);
        if (!di || !di->isInput)
            throw GraphError(fmt::format("{}: pass '{}' ({}) has no input '{}'; inputs: {}", at,
                                         e.dst, dn.type, e.dstPort, portList(dn.refl, true)));
        if (so->kind != di->kind)
            throw GraphError(fmt::format("{}: {}.{} is a {} but {}.{} expects a {}", at, e.src,
                                         e.srcPort, kindName(so->kind), e.dst, e.dstPort,
                                         kindName(di->kind)));
        if (so->kind == ResourceKind::Texture && di->format && so->format &&
            *di->format != *so->format)
            throw GraphError(fmt::format("{}: format mismatch: {}.{} is {} but {}.{} expects {}",
                                         at, e.src, e.srcPort, gpu::formatName(*so->format), e.dst,
                                         e.dstPort, gpu::formatName(*di->format)));
        std::string key = e.dst + "." + e.dstPort;
        if (inputSource.count(key))
            throw GraphError(fmt::format("{}: input {} already has an edge from {}.{}", at, key,
                                         inputSource[key]->src, inputSource[key]->srcPort));
        inputSource[key] = &e;
    }

    if (g.outputs.empty())
        throw GraphError(g.outputsWhere +
                         ": graph has no marked output; add \"outputs\": [\"pass.port\"]");
    for (size_t i = 0; i < g.outputs.size(); ++i) {
        auto dot = g.outputs[i].find('.');
        std::string node = g.outputs[i].substr(0, dot);
        std::string port = dot == std::string::npos ? "" : g.outputs[i].substr(dot + 1);
        const std::string& at = g.outputWhere[i];
        int ni = g.find(node);
        if (ni < 0)
            throw GraphError(at + ": output '" + g.outputs[i] + "' names unknown pass '" + node +
                             "'; passes: " + nodeNames());
        const PortDesc* pd = g.nodes[ni].refl.findPort(port);
        if (!pd || pd->isInput)
            throw GraphError(
                fmt::format("{}: output '{}': pass '{}' has no output port '{}'; "
                            "outputs: {}",
                            at, g.outputs[i], node, port, portList(g.nodes[ni].refl, false)));
    }

    // Cycles: Kahn over every pass; what remains lies on or behind a cycle.
    const int n = int(g.nodes.size());
    std::vector<int> indeg(n, 0);
    std::vector<std::vector<int>> succ(n), pred(n);
    for (auto& e : g.edges) {
        if (g.isFeedback(e)) continue;
        int s = g.find(e.src), d = g.find(e.dst);
        succ[s].push_back(d);
        pred[d].push_back(s);
        ++indeg[d];
    }
    std::vector<int> ready;
    for (int i = 0; i < n; ++i)
        if (indeg[i] == 0) ready.push_back(i);
    int visited = 0;
    while (!ready.empty()) {
        int i = ready.back();
        ready.pop_back();
        ++visited;
        for (int s : succ[i])
            if (--indeg[s] == 0) ready.push_back(s);
    }
    if (visited != n) {
        std::vector<int> remaining;
        for (int i = 0; i < n; ++i)
            if (indeg[i] > 0) remaining.push_back(i);
        auto cycle = findCycle(g, remaining, pred);
        throw GraphError(g.nodes[g.find(cycle.front())].where +
                         ": graph has a cycle: " + joinNames(cycle, " -> "));
    }
}

// ---------------------------------------------------------------------------------------------
// Stage 2: cull

CullResult cull(const GraphModel& g) {
    CullResult c;
    c.keep.assign(g.nodes.size(), false);
    std::vector<std::string> stack;
    for (auto& o : g.outputs) stack.push_back(o.substr(0, o.find('.')));
    while (!stack.empty()) {
        int n = g.find(stack.back());
        stack.pop_back();
        if (n < 0 || c.keep[n]) continue;
        c.keep[n] = true;
        for (auto& e : g.edges)
            if (e.dst == g.nodes[n].name) stack.push_back(e.src);
    }
    for (size_t i = 0; i < g.nodes.size(); ++i)
        if (!c.keep[i]) c.culled.push_back(g.nodes[i].name);

    // Required inputs of kept passes must be connected.
    for (size_t i = 0; i < g.nodes.size(); ++i) {
        if (!c.keep[i]) continue;
        const auto& n = g.nodes[i];
        for (auto& port : n.refl.ports()) {
            if (!port.isInput || port.optional) continue;
            bool connected = std::any_of(g.edges.begin(), g.edges.end(), [&](auto& e) {
                return e.dst == n.name && e.dstPort == port.name;
            });
            if (connected) continue;
            std::string writer;
            for (auto& o : n.refl.ports())
                if (!o.isInput && o.inPlaceOf == port.name) writer = o.name;
            throw GraphError(fmt::format(
                "{}: pass '{}' ({}): required input '{}' is not connected{}", n.where, n.name,
                n.type, port.name,
                writer.empty() ? ""
                               : fmt::format(" (output '{}' is written in place of it; declare "
                                             "the input optional to allocate the output instead)",
                                             writer)));
        }
    }
    return c;
}

// ---------------------------------------------------------------------------------------------
// Stage 3: order

OrderResult order(const GraphModel& g, const CullResult& c) {
    const int n = int(g.nodes.size());
    OrderResult o;
    std::vector<std::vector<int>> succ(n), pred(n);
    auto addEdge = [&](int a, int b) {
        succ[a].push_back(b);
        pred[b].push_back(a);
    };
    for (auto& e : g.edges) {
        int s = g.find(e.src), d = g.find(e.dst);
        if (c.keep[s] && c.keep[d] && !g.isFeedback(e)) addEdge(s, d);
    }

    // In-place writes: one writer per value, and every other reader of that value runs first.
    std::map<std::string, std::pair<int, std::string>> writer;  // "node.port" -> {pass, output}
    for (int w = 0; w < n; ++w) {
        if (!c.keep[w]) continue;
        for (auto [out, in] : inPlaceWrites(g, w)) {
            std::string value = in->src + "." + in->srcPort;
            auto prev = writer.find(value);
            if (prev != writer.end())
                throw GraphError(fmt::format(
                    "{}: passes '{}' (output '{}') and '{}' (output '{}') both write {} in place; "
                    "nothing orders two in-place writers of one value: chain them ({}.{} -> "
                    "{}.{}) or give one of them an output of its own",
                    g.nodes[w].where, g.nodes[prev->second.first].name, prev->second.second,
                    g.nodes[w].name, out->name, value, g.nodes[prev->second.first].name,
                    prev->second.second, g.nodes[w].name, out->inPlaceOf));
            writer[value] = {w, out->name};
            for (auto& e : g.edges) {
                if (e.isExecutionOnly() || e.src + "." + e.srcPort != value) continue;
                int r = g.find(e.dst);
                if (!c.keep[r]) continue;
                // Previous-frame readers count too: the history copy of `value` is refreshed
                // after they read it and before the write (stage 5), which no pass can do for
                // the writer itself.
                if (r == w && g.isFeedback(e))
                    throw GraphError(fmt::format(
                        "{}: pass '{}' ({}): input '{}' reads the previous frame of {}, which the "
                        "pass also writes in place (output '{}'); the history copy cannot be "
                        "refreshed in the middle of the pass: give '{}' an output of its own",
                        g.nodes[w].where, g.nodes[w].name, g.nodes[w].type, e.dstPort, value,
                        out->name, out->name));
                if (r == w) continue;
                OrderingEdge oe{e.dst, g.nodes[w].name, value, g.isFeedback(e)};
                if (std::find(o.inPlaceEdges.begin(), o.inPlaceEdges.end(), oe) !=
                    o.inPlaceEdges.end())
                    continue;
                o.inPlaceEdges.push_back(oe);
                addEdge(r, w);
            }
        }
    }

    // Kahn; ties keep declaration order (determinism).
    std::vector<int> indeg(n, 0);
    int kept = 0;
    for (int i = 0; i < n; ++i) {
        kept += c.keep[i];
        for (int s : succ[i]) ++indeg[s];
    }
    std::vector<bool> done(n, false);
    o.position.assign(n, -1);
    while (int(o.order.size()) < kept) {
        int pick = -1;
        for (int i = 0; i < n && pick < 0; ++i)
            if (!done[i] && c.keep[i] && indeg[i] == 0) pick = i;
        if (pick < 0) {
            // Validation rejected data cycles, so an in-place ordering edge closed this one.
            std::vector<int> remaining;
            for (int i = 0; i < n; ++i)
                if (c.keep[i] && !done[i] && indeg[i] > 0) remaining.push_back(i);
            auto cycle = findCycle(g, remaining, pred);
            std::string why;
            for (auto& e : o.inPlaceEdges)
                for (size_t k = 0; k + 1 < cycle.size(); ++k)
                    if (cycle[k] == e.before && cycle[k + 1] == e.after && why.empty())
                        why = fmt::format(
                            "'{}' writes {} in place, so '{}', which reads {}{}, must run "
                            "before it",
                            e.after, e.resource, e.before, e.resource,
                            e.previousFrame ? " of the previous frame" : "");
            throw GraphError(
                fmt::format("{}: in-place write cannot be ordered: {}; but the "
                            "graph also needs {}",
                            g.nodes[g.find(cycle.front())].where, why, joinNames(cycle, " -> ")));
        }
        done[pick] = true;
        o.position[pick] = int(o.order.size());
        o.order.push_back(pick);
        for (int s : succ[pick]) --indeg[s];
    }
    return o;
}

// ---------------------------------------------------------------------------------------------
// Stage 4: create resources

void applySize(CompiledGraph::Resource& r, const SizeRule& s, uint32_t width, uint32_t height) {
    if (r.kind == ResourceKind::Texture) {
        if (s.mode == SizeRule::Mode::Fixed) {
            r.width = s.width;
            r.height = s.height;
        } else {
            r.width = std::max(1u, uint32_t(std::lround(width * s.scale)));
            r.height = std::max(1u, uint32_t(std::lround(height * s.scale)));
        }
    } else {
        r.bytes = s.mode == SizeRule::Mode::Fixed
                      ? s.bytes
                      : s.bytesPerPixel * uint64_t(width) * height + s.extraBytes;
        r.bytes = std::max<uint64_t>(r.bytes, 4);
    }
}

ResourcePlan createResources(const GraphModel& g, const CullResult& c, const OrderResult& o,
                             uint32_t width, uint32_t height) {
    ResourcePlan plan;
    const int end = int(o.order.size());
    auto isMarked = [&](const std::string& key) {
        return std::find(g.outputs.begin(), g.outputs.end(), key) != g.outputs.end();
    };
    for (int pos = 0; pos < end; ++pos) {
        const auto& node = g.nodes[o.order[pos]];
        for (auto& port : node.refl.ports()) {
            if (port.isInput) continue;
            std::string key = node.name + "." + port.name;
            bool isOutput = isMarked(key);
            int last = isOutput ? end : pos;
            bool consumed = false;
            for (auto& e : g.edges)
                if (e.src == node.name && e.srcPort == port.name && c.keep[g.find(e.dst)]) {
                    consumed = true;
                    // Feedback sources live until their history copy (stage 5).
                    if (!g.isFeedback(e)) last = std::max(last, o.position[g.find(e.dst)]);
                }
            CompiledGraph::Resource r;
            r.name = key;
            r.kind = port.kind;
            r.format = port.format.value_or(gpu::Format::RGBA32F);
            applySize(r, port.size, width, height);

            // In place: this output is its input's resource, which now lives on to this
            // output's readers. An unconnected (optional) input falls through to a resource of
            // its own.
            const GraphEdge* in =
                port.inPlaceOf.empty() ? nullptr : g.inputEdge(node.name, port.inPlaceOf);
            if (in) {
                std::string value = in->src + "." + in->srcPort;
                auto it = plan.portResource.find(value);
                if (it == plan.portResource.end())
                    throw GraphError(
                        fmt::format("internal: no resource for {} (in place of {})", value, key));
                auto& target = plan.resources[it->second];
                bool same = target.kind == r.kind &&
                            (r.kind == ResourceKind::Texture
                                 ? target.format == r.format && target.width == r.width &&
                                       target.height == r.height
                                 : target.bytes == r.bytes);
                if (!same)
                    throw GraphError(fmt::format(
                        "{}: pass '{}' ({}): in-place output '{}' is a {} but input '{}' is "
                        "connected to {}, a {}; an in-place output must match its input's "
                        "resource in kind, format and size",
                        node.where, node.name, node.type, port.name, describe(r), port.inPlaceOf,
                        value, describe(target)));
                if (isMarked(value))
                    throw GraphError(fmt::format(
                        "{}: pass '{}' ({}): output '{}' overwrites {} in place, but {} is a "
                        "marked graph output and must keep its value; mark {} instead, or write "
                        "a new output",
                        node.where, node.name, node.type, port.name, value, value, key));
                target.lastUse = std::max(target.lastUse, last);
                target.graphOutput = target.graphOutput || isOutput;
                target.inPlaceWriters.push_back(key);
                plan.portResource[key] = it->second;
                continue;
            }
            if (port.optional && !consumed && !isOutput) continue;
            r.firstUse = pos;
            r.lastUse = last;
            r.graphOutput = isOutput;
            plan.portResource[key] = int(plan.resources.size());
            plan.resources.push_back(r);
        }
        for (auto& pd : node.refl.persistent()) {
            CompiledGraph::Resource r;
            r.name = node.name + "#" + pd.name;
            r.kind = pd.kind;
            r.format = pd.format;
            applySize(r, pd.size, width, height);
            r.firstUse = 0;
            r.lastUse = end;
            r.persistent = true;
            plan.portResource[r.name] = int(plan.resources.size());
            plan.resources.push_back(r);
        }
        // Scratch lives only while its pass executes.
        for (auto& sd : node.refl.scratch()) {
            CompiledGraph::Resource r;
            r.name = node.name + "." + sd.name;
            r.kind = sd.kind;
            r.format = sd.format.value_or(gpu::Format::RGBA32F);
            applySize(r, sd.size, width, height);
            r.firstUse = r.lastUse = pos;
            r.scratch = true;
            plan.portResource[r.name] = int(plan.resources.size());
            plan.resources.push_back(r);
        }
    }
    // Inputs point at their producer's resource (previous-frame inputs: stage 5).
    for (auto& e : g.edges) {
        if (e.isExecutionOnly() || !c.keep[g.find(e.dst)] || g.isFeedback(e)) continue;
        auto it = plan.portResource.find(e.src + "." + e.srcPort);
        if (it == plan.portResource.end()) continue;
        plan.portResource[e.dst + "." + e.dstPort] = it->second;
    }
    return plan;
}

// ---------------------------------------------------------------------------------------------
// Stage 5: feedback

ResourcePlan feedback(const GraphModel& g, const CullResult& c, const OrderResult& o,
                      ResourcePlan plan) {
    const int end = int(o.order.size());
    for (auto& e : g.edges) {
        if (!g.isFeedback(e) || !c.keep[g.find(e.dst)]) continue;
        std::string srcKey = e.src + "." + e.srcPort;
        auto it = plan.portResource.find(srcKey);
        if (it == plan.portResource.end()) continue;
        int ri = it->second;
        std::string histKey = srcKey + "@prev";
        auto h = plan.portResource.find(histKey);
        if (h == plan.portResource.end()) {
            // Usually the copy runs at the end of the frame. When a later pass overwrites
            // srcKey in place, it runs once the producer and every previous-frame reader are
            // done; stage 3 ordered those readers before the writer.
            bool overwritten = false;
            for (int w = 0; w < int(g.nodes.size()); ++w)
                if (c.keep[w])
                    for (auto [out, in] : inPlaceWrites(g, w))
                        overwritten |= in->src + "." + in->srcPort == srcKey;
            int copyAt = end;
            if (overwritten) {
                copyAt = o.position[g.find(e.src)];
                for (auto& f : g.edges)
                    if (g.isFeedback(f) && f.src + "." + f.srcPort == srcKey &&
                        c.keep[g.find(f.dst)])
                        copyAt = std::max(copyAt, o.position[g.find(f.dst)]);
            }
            CompiledGraph::Resource r = plan.resources[ri];
            r.name = histKey;
            r.firstUse = 0;
            r.lastUse = end;
            r.persistent = true;
            r.graphOutput = false;
            r.scratch = false;
            r.inPlaceWriters.clear();
            r.historyOf = ri;
            r.historyCopyAt = copyAt;
            plan.resources[ri].lastUse = std::max(plan.resources[ri].lastUse, copyAt);
            h = plan.portResource.emplace(histKey, int(plan.resources.size())).first;
            plan.resources.push_back(r);
        }
        plan.portResource[e.dst + "." + e.dstPort] = h->second;
    }
    return plan;
}

// ---------------------------------------------------------------------------------------------
// Stage 6: alias

AliasResult alias(const std::vector<CompiledGraph::Resource>& resources, bool enabled) {
    struct Slot {
        int lastUse;
        int desc;
        bool shareable;
    };
    AliasResult a;
    a.physical.assign(resources.size(), -1);
    std::vector<Slot> slots;
    std::vector<int> byFirstUse(resources.size());
    for (size_t i = 0; i < byFirstUse.size(); ++i) byFirstUse[i] = int(i);
    std::stable_sort(byFirstUse.begin(), byFirstUse.end(),
                     [&](int x, int y) { return resources[x].firstUse < resources[y].firstUse; });
    for (int ri : byFirstUse) {
        const auto& r = resources[ri];
        bool shareable = enabled && !r.persistent && !r.graphOutput && r.historyOf < 0;
        if (shareable) {
            for (size_t s = 0; s < slots.size(); ++s) {
                const auto& d = resources[slots[s].desc];
                if (slots[s].shareable && slots[s].lastUse < r.firstUse && d.kind == r.kind &&
                    d.format == r.format && d.width == r.width && d.height == r.height &&
                    d.bytes == r.bytes) {
                    a.physical[ri] = int(s);
                    slots[s].lastUse = r.lastUse;
                    break;
                }
            }
        }
        if (a.physical[ri] < 0) {
            a.physical[ri] = int(slots.size());
            slots.push_back({r.lastUse, ri, shareable});
        }
    }
    a.physicalCount = int(slots.size());
    return a;
}

}  // namespace loom::stages
