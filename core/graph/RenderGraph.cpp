#include "core/graph/RenderGraph.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "core/graph/CompileStages.h"
#include "core/util/AtomicFile.h"
#include "core/util/Hash.h"
#include "core/util/Log.h"

namespace loom {

namespace {

// "node.port" -> {node, port}; "node" -> {node, ""}.
std::pair<std::string, std::string> splitPort(const std::string& s) {
    auto dot = s.find('.');
    if (dot == std::string::npos) return {s, ""};
    return {s.substr(0, dot), s.substr(dot + 1)};
}

std::string joinNames(const std::vector<std::string>& names, const char* sep = ", ") {
    std::string out;
    for (auto& n : names) out += (out.empty() ? "" : sep) + n;
    return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// ExecuteContext

std::shared_ptr<gpu::Image> ExecuteContext::texture(const std::string& port) const {
    auto it = mTextures.find(port);
    return it == mTextures.end() ? nullptr : it->second;
}
std::shared_ptr<gpu::Buffer> ExecuteContext::buffer(const std::string& port) const {
    auto it = mBuffers.find(port);
    return it == mBuffers.end() ? nullptr : it->second;
}
std::shared_ptr<gpu::Image> ExecuteContext::persistentTexture(const std::string& name) const {
    return texture("#" + name);
}
std::shared_ptr<gpu::Buffer> ExecuteContext::persistentBuffer(const std::string& name) const {
    return buffer("#" + name);
}
std::shared_ptr<gpu::Image> ExecuteContext::scratchTexture(const std::string& name) const {
    auto t = texture("%" + name);
    if (!t) throw UserError("no scratch texture '" + name + "' declared in reflect()");
    return t;
}
std::shared_ptr<gpu::Buffer> ExecuteContext::scratchBuffer(const std::string& name) const {
    auto b = buffer("%" + name);
    if (!b) throw UserError("no scratch buffer '" + name + "' declared in reflect()");
    return b;
}
const scene::SceneGpu& ExecuteContext::scene() const {
    if (!mFrame.scene)
        throw UserError("this pass needs a scene; pass one with --scene FILE (or scene= in Lua)");
    return *mFrame.scene;
}

bool ExecuteContext::has(const std::string& port) const {
    return mTextures.count(port) || mBuffers.count(port);
}

std::string ExecuteContext::portOf(const gpu::Buffer* buffer) const {
    for (auto& [port, b] : mBuffers)
        if (b.get() == buffer) return port;
    return "";
}

// ---------------------------------------------------------------------------------------------
// Loading and saving

std::string RenderGraph::where(const std::string& pointer) const {
    if (mSource) return mSource->where(pointer);
    return mSourceFile.empty() ? "graph '" + mName + "'" : mSourceFile;
}

std::string RenderGraph::sourceDir() const {
    if (mSourceFile.empty()) return std::filesystem::current_path().string();
    return std::filesystem::absolute(mSourceFile).parent_path().string();
}

std::unique_ptr<RenderGraph> RenderGraph::load(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw GraphError(path + ": cannot open graph file");
    std::stringstream ss;
    ss << in.rdbuf();
    return parse(ss.str(), path);
}

std::unique_ptr<RenderGraph> RenderGraph::parse(const std::string& text,
                                                const std::string& filename) {
    auto g = std::make_unique<RenderGraph>();
    g->mSourceFile = filename;
    g->mSource = std::make_shared<JsonSource>(JsonSource::parse(text, filename));
    const json& root = g->mSource->root();
    auto fail = [&](const std::string& ptr, const std::string& msg) {
        return GraphError(g->where(ptr) + ": " + msg);
    };
    if (!root.is_object()) throw fail("", "a graph must be a JSON object");
    for (auto& [key, v] : root.items())
        if (key != "name" && key != "passes" && key != "edges" && key != "outputs" &&
            key != "description")
            throw fail("/" + key, "unknown graph field '" + key +
                                      "'; valid fields: name, description, passes, edges, outputs");
    if (root.contains("name")) {
        if (!root["name"].is_string()) throw fail("/name", "'name' must be a string");
        g->mName = root["name"];
    }
    if (root.contains("description")) {
        if (!root["description"].is_string())
            throw fail("/description", "'description' must be a string");
        g->mDescription = root["description"];
    }
    if (!root.contains("passes") || !root["passes"].is_array())
        throw fail("/passes", "a graph needs a 'passes' array");

    // Passes.
    const json& passes = root["passes"];
    for (size_t i = 0; i < passes.size(); ++i) {
        std::string ptr = "/passes/" + std::to_string(i);
        const json& p = passes[i];
        if (!p.is_object()) throw fail(ptr, "each pass must be an object with 'name' and 'type'");
        for (auto& [key, v] : p.items())
            if (key != "name" && key != "type" && key != "params")
                throw fail(ptr + "/" + key,
                           "unknown pass field '" + key + "'; valid fields: name, type, params");
        if (!p.contains("name") || !p["name"].is_string() || p["name"].get<std::string>().empty())
            throw fail(ptr, "pass needs a non-empty string 'name'");
        if (!p.contains("type") || !p["type"].is_string())
            throw fail(ptr, "pass '" + p["name"].get<std::string>() + "' needs a string 'type'");
        std::string name = p["name"], type = p["type"];
        if (name.find('.') != std::string::npos || name.find('#') != std::string::npos)
            throw fail(ptr + "/name", "pass name '" + name + "' must not contain '.' or '#'");
        if (g->findPass(name)) throw fail(ptr + "/name", "duplicate pass name '" + name + "'");
        std::unique_ptr<Pass> pass;
        try {
            pass = PassRegistry::instance().create(type, name);
            pass->setBaseDir(g->sourceDir());
        } catch (const UserError& e) {
            throw fail(ptr + "/type", "pass '" + name + "': " + e.what());
        }
        g->mPassWhere[name] = ptr;
        if (p.contains("params")) {
            if (!p["params"].is_object())
                throw fail(ptr + "/params", "pass '" + name + "': 'params' must be an object");
            // Parameters may declare further parameters (ComputePass constants), so set
            // what is declared until nothing changes; what is left is unknown.
            std::vector<std::string> pending;
            for (auto& [key, v] : p["params"].items()) pending.push_back(key);
            bool progress = true;
            while (!pending.empty() && progress) {
                progress = false;
                PassReflection r = pass->reflection();
                for (auto it = pending.begin(); it != pending.end();) {
                    if (!r.findParam(*it)) {
                        ++it;
                        continue;
                    }
                    try {
                        pass->setParam(*it, p["params"][*it]);
                    } catch (const UserError& e) {
                        throw fail(ptr + "/params/" + *it,
                                   "pass '" + name + "' (" + type + "): " + e.what());
                    }
                    it = pending.erase(it);
                    progress = true;
                }
            }
            if (!pending.empty()) {
                try {
                    pass->setParam(pending.front(), p["params"][pending.front()]);
                } catch (const UserError& e) {
                    throw fail(ptr + "/params/" + pending.front(), e.what());
                }
            }
        }
        g->mPasses.push_back(std::move(pass));
    }

    // Edges.
    if (root.contains("edges")) {
        if (!root["edges"].is_array()) throw fail("/edges", "'edges' must be an array");
        const json& edges = root["edges"];
        for (size_t i = 0; i < edges.size(); ++i) {
            std::string ptr = "/edges/" + std::to_string(i);
            const json& e = edges[i];
            if (!e.is_array() || e.size() != 2 || !e[0].is_string() || !e[1].is_string())
                throw fail(ptr,
                           "an edge is [\"src.port\", \"dst.port\"] (or [\"src\", \"dst\"] "
                           "for an execution-only dependency)");
            auto [s, sp] = splitPort(e[0]);
            auto [d, dp] = splitPort(e[1]);
            if (sp.empty() != dp.empty())
                throw fail(ptr, "edge mixes a port and a pass: name ports on both ends or on none");
            g->mEdges.push_back({s, sp, d, dp, g->where(ptr)});
        }
    }
    // Outputs.
    if (root.contains("outputs")) {
        if (!root["outputs"].is_array()) throw fail("/outputs", "'outputs' must be an array");
        for (size_t i = 0; i < root["outputs"].size(); ++i) {
            const json& o = root["outputs"][i];
            if (!o.is_string())
                throw fail("/outputs/" + std::to_string(i), "an output is a \"pass.port\" string");
            g->mOutputs.push_back(o);
        }
    }
    g->validate();
    return g;
}

json RenderGraph::toJson() const {
    json j;
    j["name"] = mName;
    if (!mDescription.empty()) j["description"] = mDescription;
    j["passes"] = json::array();
    for (const auto& p : mPasses) {
        json pj{{"name", p->name()}, {"type", p->type()}};
        json params = json::object();
        for (const auto& [k, v] : p->params()) params[k] = v;
        if (!params.empty()) pj["params"] = params;
        j["passes"].push_back(pj);
    }
    j["edges"] = json::array();
    for (const auto& e : mEdges) {
        if (e.isExecutionOnly())
            j["edges"].push_back({e.src, e.dst});
        else
            j["edges"].push_back({e.src + "." + e.srcPort, e.dst + "." + e.dstPort});
    }
    j["outputs"] = mOutputs;
    return j;
}

void RenderGraph::save(const std::string& path) const {
    validate();  // never save a graph that would not load
    writeTextFileAtomic(path, "graph file", toJson().dump(2) + "\n");
}

bool RenderGraph::equals(const RenderGraph& other) const {
    return toJson() == other.toJson();
}

// ---------------------------------------------------------------------------------------------
// Editing

Pass* RenderGraph::findPass(const std::string& name) const {
    for (auto& p : mPasses)
        if (p->name() == name) return p.get();
    return nullptr;
}

Pass& RenderGraph::addPass(const std::string& type, const std::string& name, const json& params) {
    if (name.empty() || name.find('.') != std::string::npos || name.find('#') != std::string::npos)
        throw GraphError("invalid pass name '" + name + "' (non-empty, no '.' or '#')");
    if (findPass(name)) throw GraphError("a pass named '" + name + "' already exists");
    auto pass = PassRegistry::instance().create(type, name);
    pass->setBaseDir(sourceDir());
    if (params.is_object())
        for (auto& [k, v] : params.items()) pass->setParam(k, v);
    mPasses.push_back(std::move(pass));
    invalidate("pass '" + name + "' added");
    return *mPasses.back();
}

void RenderGraph::removePass(const std::string& name) {
    auto it =
        std::find_if(mPasses.begin(), mPasses.end(), [&](auto& p) { return p->name() == name; });
    if (it == mPasses.end()) throw GraphError("no pass named '" + name + "'");
    mPasses.erase(it);
    std::erase_if(mEdges, [&](auto& e) { return e.src == name || e.dst == name; });
    std::erase_if(mOutputs, [&](auto& o) { return splitPort(o).first == name; });
    invalidate("pass '" + name + "' removed");
}

void RenderGraph::connect(const std::string& from, const std::string& to) {
    auto [s, sp] = splitPort(from);
    auto [d, dp] = splitPort(to);
    if (sp.empty() != dp.empty())
        throw GraphError("connect: name ports on both ends (a.out, b.in) or on none (a, b)");
    GraphEdge e{s, sp, d, dp, "connect(" + from + ", " + to + ")"};
    mEdges.push_back(e);
    try {
        validate();
    } catch (...) {
        mEdges.pop_back();
        throw;
    }
    invalidate("edge added");
}

void RenderGraph::disconnect(const std::string& from, const std::string& to) {
    auto [s, sp] = splitPort(from);
    auto [d, dp] = splitPort(to);
    GraphEdge e{s, sp, d, dp, ""};
    auto n = std::erase_if(mEdges, [&](auto& x) { return x == e; });
    if (!n) throw GraphError("no edge " + from + " -> " + to);
    invalidate("edge removed");
}

void RenderGraph::markOutput(const std::string& port) {
    if (std::find(mOutputs.begin(), mOutputs.end(), port) != mOutputs.end()) return;
    mOutputs.push_back(port);
    try {
        validate();
    } catch (...) {
        mOutputs.pop_back();
        throw;
    }
    invalidate("output marked");
}

void RenderGraph::unmarkOutput(const std::string& port) {
    if (!std::erase(mOutputs, port)) throw GraphError("'" + port + "' is not a marked output");
    invalidate("output unmarked");
}

void RenderGraph::setParam(const std::string& passDotParam, const json& value) {
    auto [node, param] = splitPort(passDotParam);
    Pass* p = findPass(node);
    if (!p) {
        std::vector<std::string> names;
        for (auto& x : mPasses) names.push_back(x->name());
        throw GraphError("no pass named '" + node + "' (in '" + passDotParam +
                         "'); passes: " + joinNames(names));
    }
    if (param.empty()) throw GraphError("expected PASS.PARAM, got '" + passDotParam + "'");
    p->setParam(param, value);
    if (p->paramChangesPorts(param)) invalidate("ports of '" + node + "' changed");
}

json RenderGraph::getParam(const std::string& passDotParam) const {
    auto [node, param] = splitPort(passDotParam);
    Pass* p = findPass(node);
    if (!p) throw GraphError("no pass named '" + node + "'");
    return p->getParam(param);
}

// ---------------------------------------------------------------------------------------------
// Validation and compilation (no GPU): the stages live in CompileStages.cpp

stages::GraphModel RenderGraph::model() const {
    stages::GraphModel m;
    for (auto& p : mPasses) {
        auto it = mPassWhere.find(p->name());
        m.nodes.push_back({p->name(), p->type(), p->reflection(),
                           it == mPassWhere.end() ? where("") : where(it->second)});
    }
    m.edges = mEdges;
    m.outputs = mOutputs;
    for (size_t i = 0; i < mOutputs.size(); ++i)
        m.outputWhere.push_back(where("/outputs/" + std::to_string(i)));
    m.where = where("");
    m.edgesWhere = where("/edges");
    m.outputsWhere = where("/outputs");
    return m;
}

void RenderGraph::validate() const {
    stages::validate(model());
}

CompiledGraph RenderGraph::compile(uint32_t width, uint32_t height) const {
    if (width == 0 || height == 0)
        throw GraphError(fmt::format("frame size {}x{} is empty", width, height));
    const stages::GraphModel m = model();
    stages::validate(m);
    const stages::CullResult culled = stages::cull(m);
    const stages::OrderResult ordered = stages::order(m, culled);
    stages::ResourcePlan plan = stages::createResources(m, culled, ordered, width, height);
    plan = stages::feedback(m, culled, ordered, std::move(plan));
    const stages::AliasResult aliased = stages::alias(plan.resources, mAliasing);

    CompiledGraph cg;
    cg.width = width;
    cg.height = height;
    cg.order = ordered.order;
    cg.culled = culled.culled;
    for (auto& e : ordered.inPlaceEdges) cg.inPlaceEdges.push_back({e.before, e.after});
    cg.resources = std::move(plan.resources);
    for (size_t i = 0; i < cg.resources.size(); ++i) cg.resources[i].physical = aliased.physical[i];
    cg.physicalCount = aliased.physicalCount;
    cg.portResource = std::move(plan.portResource);
    return cg;
}

std::string RenderGraph::toGraphviz() const {
    std::string s = "digraph \"" + mName + "\" {\n  rankdir=LR;\n  node [shape=box];\n";
    for (auto& p : mPasses)
        s += fmt::format("  \"{}\" [label=\"{}\\n({})\"];\n", p->name(), p->name(), p->type());
    for (auto& e : mEdges) {
        if (e.isExecutionOnly())
            s += fmt::format("  \"{}\" -> \"{}\" [style=dashed];\n", e.src, e.dst);
        else
            s += fmt::format("  \"{}\" -> \"{}\" [label=\"{} -> {}\"];\n", e.src, e.dst, e.srcPort,
                             e.dstPort);
    }
    for (auto& o : mOutputs)
        s += fmt::format("  \"out:{}\" [shape=ellipse];\n  \"{}\" -> \"out:{}\";\n", o,
                         splitPort(o).first, o);
    return s + "}\n";
}

// ---------------------------------------------------------------------------------------------
// Execution

void RenderGraph::invalidate(const std::string& reason) {
    if (mCompiled && (!mPersistentTextures.empty() || !mPersistentBuffers.empty()))
        logInfo("graph '{}': {}; persistent resources reset", mName, reason);
    mCompiled.reset();
    mPassesCompiled = false;
}

void RenderGraph::allocate(gpu::Context& gpu) {
    const auto& cg = *mCompiled;
    mPhysical.assign(cg.physicalCount, nullptr);
    std::map<std::string, std::shared_ptr<gpu::Image>> oldTex;
    std::map<std::string, std::shared_ptr<gpu::Buffer>> oldBuf;
    mPersistentTextures.clear();
    mPersistentBuffers.clear();
    mFreshHistory.clear();
    for (const auto& r : cg.resources) {
        if (mPhysical[r.physical]) continue;
        // Device limits and out-of-memory name the resource (pass.port) and its size.
        try {
            if (r.kind == ResourceKind::Texture) {
                auto img = gpu.createImage(r.width, r.height, r.format, r.name);
                mPhysical[r.physical] = img;
                if (r.persistent) mPersistentTextures[r.name] = img;
            } else {
                auto buf = gpu.createBuffer(r.bytes, r.name);
                auto cmd = gpu.beginCommands();
                cmd->fillBuffer(*buf, 0);
                gpu.submit(*cmd);
                mPhysical[r.physical] = buf;
                if (r.persistent) mPersistentBuffers[r.name] = buf;
            }
        } catch (const UserError& e) {
            std::string size =
                r.kind == ResourceKind::Texture
                    ? fmt::format("{}x{} {}", r.width, r.height, gpu::formatName(r.format))
                    : fmt::format("{} bytes", r.bytes);
            throw UserError(
                fmt::format("graph '{}': resource {} ({}): {}", mName, r.name, size, e.what()));
        }
    }
    resetHistory();
}

void RenderGraph::resetHistory() {
    if (!mCompiled) return;
    const auto& cg = *mCompiled;
    for (const auto& r : cg.resources)
        if (r.persistent && r.historyOf < 0)
            mFreshHistory.insert(r.name.substr(0, r.name.find('#')));
    // Consumers of a history copy see historyReset() until it holds a frame.
    for (const auto& [key, ri] : cg.portResource)
        if (cg.resources[ri].historyOf >= 0 && key.find('@') == std::string::npos)
            mFreshHistory.insert(splitPort(key).first);
}

void RenderGraph::compilePasses(ShaderLibrary& shaders, const std::vector<int>& order) {
    for (int pi : order) {
        try {
            mPasses[pi]->compile(shaders);
        } catch (const UserError& e) {
            throw UserError(fmt::format("pass '{}' ({}): {}", mPasses[pi]->name(),
                                        mPasses[pi]->type(), e.what()));
        }
    }
    mPassesCompiled = true;
}

void RenderGraph::execute(gpu::Context& gpu, ShaderLibrary& shaders, uint32_t width,
                          uint32_t height, const FrameInputs& frame) {
    if (mCompiled && (mCompiled->width != width || mCompiled->height != height))
        invalidate(fmt::format("resized to {}x{}", width, height));
    if (!mCompiled) {
        mCompiled = compile(width, height);
        for (auto& c : mCompiled->culled)
            logDebug("graph '{}': pass '{}' feeds no output and is culled", mName, c);
        allocate(gpu);
        ++mCompileGeneration;
    }
    if (!mPassesCompiled) compilePasses(shaders, mCompiled->order);

    const auto& cg = *mCompiled;
    auto cmd = gpu.beginCommands();
    // Feedback edges: keep a value for the next frame's previous-frame inputs, at the end of
    // the frame or, when a later pass overwrites it in place, before that write (stage 5).
    auto copyHistory = [&](int at) {
        bool any = false;
        for (const auto& r : cg.resources) {
            if (r.historyOf < 0 || r.historyCopyAt != at) continue;
            const auto& src = cg.resources[r.historyOf];
            if (r.kind == ResourceKind::Texture)
                cmd->copyImage(*std::static_pointer_cast<gpu::Image>(mPhysical[src.physical]),
                               *std::static_pointer_cast<gpu::Image>(mPhysical[r.physical]));
            else
                cmd->copyBuffer(*std::static_pointer_cast<gpu::Buffer>(mPhysical[src.physical]),
                                *std::static_pointer_cast<gpu::Buffer>(mPhysical[r.physical]),
                                r.bytes);
            any = true;
        }
        return any;
    };
    std::vector<uint32_t> stamps;
    stamps.push_back(cmd->timestamp("the frame's first commands"));
    std::map<std::string, std::set<int>> ancestors;  // for the upstream-change hash
    for (size_t pos = 0; pos < cg.order.size(); ++pos) {
        const int pi = cg.order[pos];
        Pass& pass = *mPasses[pi];
        std::set<int> anc{pi};
        for (auto& e : mEdges)
            if (e.dst == pass.name()) {
                anc.insert(ancestors[e.src].begin(), ancestors[e.src].end());
            }
        ancestors[pass.name()] = anc;
        Hasher h;
        h.add(mCompileGeneration)
            .add(frame.externalRevision)
            .add(uint64_t(width))
            .add(uint64_t(height));
        for (int a : anc) h.add(uint64_t(a)).add(mPasses[a]->revision());

        ExecuteContext ctx;
        ctx.mGpu = &gpu;
        ctx.mCmd = cmd.get();
        ctx.mShaders = &shaders;
        ctx.mPass = pass.name();
        ctx.mWidth = width;
        ctx.mHeight = height;
        ctx.mFrame = frame;
        ctx.mFrameIndex = mFrameIndex;
        ctx.mUpstreamChanged = mUpstreamHash[pass.name()] != h.h;
        mUpstreamHash[pass.name()] = h.h;
        ctx.mHistoryReset = mFreshHistory.erase(pass.name()) > 0;
        for (const auto& [key, ri] : cg.portResource) {
            auto [node, port] = splitPort(key);
            std::string local;
            if (node == pass.name()) {
                // Scratch is reached through scratchBuffer()/scratchTexture() only.
                local = cg.resources[ri].scratch ? "%" + port : port;
            } else {
                auto hash = key.find('#');
                if (hash == std::string::npos || key.substr(0, hash) != pass.name()) continue;
                local = key.substr(hash);
            }
            auto& res = mPhysical[cg.resources[ri].physical];
            if (cg.resources[ri].kind == ResourceKind::Texture)
                ctx.mTextures[local] = std::static_pointer_cast<gpu::Image>(res);
            else
                ctx.mBuffers[local] = std::static_pointer_cast<gpu::Buffer>(res);
        }
        try {
            pass.execute(ctx);
        } catch (const UserError& e) {
            throw UserError(fmt::format("pass '{}' ({}): {}", pass.name(), pass.type(), e.what()));
        } catch (const std::exception& e) {
            throw std::runtime_error(
                fmt::format("pass '{}' ({}): {}", pass.name(), pass.type(), e.what()));
        }
        cmd->barrier();
        // The in-place writer that follows must not overwrite the value before it is copied.
        if (copyHistory(int(pos))) cmd->barrier();
        stamps.push_back(cmd->timestamp(fmt::format("pass '{}' ({})", pass.name(), pass.type())));
    }
    copyHistory(int(cg.order.size()));
    gpu.submit(*cmd);
    const auto& ns = cmd->timestampsNs();
    mTimings.clear();
    for (size_t i = 0; i < cg.order.size(); ++i)
        mTimings.push_back(
            {mPasses[cg.order[i]]->name(), (ns[stamps[i + 1]] - ns[stamps[i]]) * 1e-6});
    mFrameGpuMs = (ns[stamps.back()] - ns[stamps.front()]) * 1e-6;
    for (int pi : cg.order) mPasses[pi]->frameCompleted(gpu);
    ++mFrameIndex;
}

std::shared_ptr<gpu::Image> RenderGraph::outputTexture(const std::string& port) const {
    if (!mCompiled) return nullptr;
    auto it = mCompiled->portResource.find(port);
    if (it == mCompiled->portResource.end()) return nullptr;
    const auto& r = mCompiled->resources[it->second];
    if (r.kind != ResourceKind::Texture) return nullptr;
    return std::static_pointer_cast<gpu::Image>(mPhysical[r.physical]);
}

std::shared_ptr<gpu::Buffer> RenderGraph::outputBuffer(const std::string& port) const {
    if (!mCompiled) return nullptr;
    auto it = mCompiled->portResource.find(port);
    if (it == mCompiled->portResource.end()) return nullptr;
    const auto& r = mCompiled->resources[it->second];
    if (r.kind != ResourceKind::Buffer) return nullptr;
    return std::static_pointer_cast<gpu::Buffer>(mPhysical[r.physical]);
}

void RenderGraph::setAliasing(bool enabled) {
    if (enabled == mAliasing) return;
    mAliasing = enabled;
    invalidate(enabled ? "aliasing enabled" : "aliasing disabled");
}

size_t RenderGraph::reloadShaders(ShaderLibrary& shaders) {
    size_t n = shaders.reloadChanged();
    if (n) mPassesCompiled = false;
    return n;
}

}  // namespace loom
