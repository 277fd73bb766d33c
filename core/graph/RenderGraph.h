#pragma once
// Render graph: load/save JSON, validate, compile (validate -> cull -> order -> create
// resources -> feedback -> alias), execute frame by frame with per-pass GPU timings and
// persistent resources.
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/graph/Pass.h"
#include "core/graph/ShaderLibrary.h"

namespace loom {

namespace scene {
class SceneGpu;
}
namespace stages {
struct GraphModel;
}

// Per-frame inputs from the application (CLI, Lua, inspector) to every pass.
struct FrameInputs {
    uint32_t seed = 0;
    uint64_t externalRevision = 0;           // bumped on camera moves / resets
    const scene::SceneGpu* scene = nullptr;  // nullptr when rendering without a scene
    float time = 0.0f;                       // animation time in frames
};

class GraphError : public UserError {
public:
    using UserError::UserError;
};

struct GraphEdge {
    std::string src, srcPort, dst, dstPort;  // ports empty: execution-only dependency
    std::string where;                        // source location for messages
    bool isExecutionOnly() const { return srcPort.empty(); }
    bool operator==(const GraphEdge& o) const {
        return src == o.src && srcPort == o.srcPort && dst == o.dst && dstPort == o.dstPort;
    }
};

// Result of compile(): everything decided before touching the GPU (testable without one).
struct CompiledGraph {
    struct Resource {
        std::string name;  // "node.port" or "node#persistent"
        ResourceKind kind = ResourceKind::Texture;
        gpu::Format format = gpu::Format::RGBA32F;
        uint32_t width = 0, height = 0;
        uint64_t bytes = 0;
        int firstUse = 0, lastUse = 0;  // positions in `order`
        bool persistent = false;
        bool graphOutput = false;
        bool scratch = false;  // declared scratch: lives only while its pass executes
        int historyOf = -1;  // previous-frame copy of this resource index (feedback edges)
        // History copies: the copy runs after the pass at this position in `order`; equal to
        // order.size() for the end of the frame.
        int historyCopyAt = -1;
        // Outputs ("node.port") that write this resource in place, in execution order.
        std::vector<std::string> inPlaceWriters;
        int physical = -1;  // index into physical resources; equal index = aliased memory
    };
    std::vector<int> order;                // pass indices in execution order
    std::vector<std::string> culled;       // passes that feed no output
    // Ordering edges added so that other readers of a value run before its in-place writer.
    std::vector<std::pair<std::string, std::string>> inPlaceEdges;  // {before, after}
    std::vector<Resource> resources;
    int physicalCount = 0;
    std::map<std::string, int> portResource;  // "node.port" (inputs too) -> resource index
    uint32_t width = 0, height = 0;
};

// Memory of one logical resource of a compiled graph: `loom render --timings` and the
// inspector's Memory tab both print this (RenderGraph::memoryReport()).
struct ResourceMemory {
    enum class Lifetime { Transient, Output, Scratch, Persistent, History };
    std::string name;  // node.port, node.scratch, node#persistent, node.port@prev
    ResourceKind kind = ResourceKind::Texture;
    std::string format;  // textures: "rgba32f"...; buffers: empty
    uint32_t width = 0, height = 0;
    uint64_t bytes = 0;  // textures: width * height * texel size
    Lifetime lifetime = Lifetime::Transient;
    int physical = -1;
    std::vector<std::string> aliasedWith;  // other resources sharing the same memory
    std::vector<std::string> inPlace;      // outputs written in place into this resource
};
struct MemoryReport {
    std::vector<ResourceMemory> resources;  // in CompiledGraph::resources order
    uint64_t allocatedBytes = 0;            // one per physical resource
    uint64_t unaliasedBytes = 0;            // every logical resource on its own
};
const char* lifetimeName(ResourceMemory::Lifetime l);
MemoryReport memoryReport(const CompiledGraph& cg);
// The report as a text table with totals (loom render --timings).
std::string formatMemoryReport(const MemoryReport& report);
// "12.3 MiB", "4.0 KiB", "96 B".
std::string formatBytes(uint64_t bytes);

class ExecuteContext {
public:
    gpu::Context& gpu() { return *mGpu; }
    gpu::CommandList& cmd() { return *mCmd; }
    ShaderLibrary& shaders() { return *mShaders; }
    // nullptr when an optional port is unconnected (or an optional output is unused).
    std::shared_ptr<gpu::Image> texture(const std::string& port) const;
    std::shared_ptr<gpu::Buffer> buffer(const std::string& port) const;
    std::shared_ptr<gpu::Image> persistentTexture(const std::string& name) const;
    std::shared_ptr<gpu::Buffer> persistentBuffer(const std::string& name) const;
    // Declared scratch (PassReflection::scratchBuffer / scratchTexture); valid only during this
    // execute(): the memory may belong to other passes' transient resources before and after.
    // Contents are undefined on entry. Throw UserError when the pass declared no such scratch.
    std::shared_ptr<gpu::Image> scratchTexture(const std::string& name) const;
    std::shared_ptr<gpu::Buffer> scratchBuffer(const std::string& name) const;
    bool has(const std::string& port) const;
    // The port (or persistent resource) a buffer is bound to in this pass, "" if none.
    std::string portOf(const gpu::Buffer* buffer) const;
    uint32_t width() const { return mWidth; }
    uint32_t height() const { return mHeight; }
    uint64_t frameIndex() const { return mFrameIndex; }
    uint32_t seed() const { return mFrame.seed; }
    // The scene on the GPU; throws UserError naming the pass when none was loaded.
    const scene::SceneGpu& scene() const;
    bool hasScene() const { return mFrame.scene != nullptr; }
    float time() const { return mFrame.time; }
    // True when anything upstream (parameters, graph, size, camera) changed since this pass
    // last ran; Accumulate resets on it.
    bool upstreamChanged() const { return mUpstreamChanged; }
    // True when the pass's persistent resources were just (re)allocated.
    bool historyReset() const { return mHistoryReset; }

private:
    friend class RenderGraph;
    gpu::Context* mGpu = nullptr;
    gpu::CommandList* mCmd = nullptr;
    ShaderLibrary* mShaders = nullptr;
    std::string mPass;
    std::map<std::string, std::shared_ptr<gpu::Image>> mTextures;
    std::map<std::string, std::shared_ptr<gpu::Buffer>> mBuffers;
    uint32_t mWidth = 0, mHeight = 0;
    FrameInputs mFrame;
    uint64_t mFrameIndex = 0;
    bool mUpstreamChanged = false, mHistoryReset = false;
};

struct PassTiming {
    std::string pass;
    double gpuMs = 0.0;
};

class RenderGraph {
public:
    RenderGraph() = default;
    // Load from a JSON file / text. Throws GraphError naming file:line:col, node and field.
    static std::unique_ptr<RenderGraph> load(const std::string& path);
    static std::unique_ptr<RenderGraph> parse(const std::string& text, const std::string& filename);
    json toJson() const;
    void save(const std::string& path) const;
    // Structural equality, parameters included (JSON round trip).
    bool equals(const RenderGraph& other) const;

    // Editing (Lua, inspector). Each validates what it can immediately.
    Pass& addPass(const std::string& type, const std::string& name, const json& params = {});
    void removePass(const std::string& name);
    void connect(const std::string& from, const std::string& to);  // "a.out", "b.in" or "a","b"
    void disconnect(const std::string& from, const std::string& to);
    void markOutput(const std::string& port);
    void unmarkOutput(const std::string& port);
    void setParam(const std::string& passDotParam, const json& value);
    json getParam(const std::string& passDotParam) const;

    Pass* findPass(const std::string& name) const;
    const std::vector<std::unique_ptr<Pass>>& passes() const { return mPasses; }
    const std::vector<GraphEdge>& edges() const { return mEdges; }
    const std::vector<std::string>& outputs() const { return mOutputs; }
    const std::string& name() const { return mName; }
    const std::string& description() const { return mDescription; }
    const std::string& sourceFile() const { return mSourceFile; }
    std::string sourceDir() const;

    // Stages (core/graph/CompileStages.h): validate -> cull -> order -> createResources ->
    // feedback -> alias. Pure CPU; throws GraphError.
    CompiledGraph compile(uint32_t width, uint32_t height) const;
    // Compiles the shaders of the passes at `order` (indices into passes()), which checks each
    // ComputePass declaration against its shader; errors name the pass. execute() calls it,
    // and loom validate, so that a graph that validates also compiles.
    void compilePasses(ShaderLibrary& shaders, const std::vector<int>& order);
    void validate() const;
    // The graph as the compile stages see it (declarations, edges, outputs, locations).
    stages::GraphModel model() const;
    // Per-resource memory of the last compile (empty before the first frame).
    MemoryReport memoryReport() const;
    std::string toGraphviz() const;

    // GPU execution of one frame. Compiles on first use, after edits and on resize.
    void execute(gpu::Context& gpu, ShaderLibrary& shaders, uint32_t width, uint32_t height,
                 const FrameInputs& frame = {});
    const CompiledGraph* compiled() const { return mCompiled ? &*mCompiled : nullptr; }
    std::shared_ptr<gpu::Image> outputTexture(const std::string& port) const;
    std::shared_ptr<gpu::Buffer> outputBuffer(const std::string& port) const;
    const std::vector<PassTiming>& timings() const { return mTimings; }
    double frameGpuMs() const { return mFrameGpuMs; }
    uint64_t frameIndex() const { return mFrameIndex; }
    // Drop compiled state and persistent resources (logged); next execute recompiles.
    void invalidate(const std::string& reason);
    // Passes see historyReset() on their next execution (persistent and previous-frame data
    // are stale); nothing is reallocated.
    void resetHistory();
    // Recompile passes whose shaders changed on disk (inspector hot reload).
    size_t reloadShaders(ShaderLibrary& shaders);
    // Memory aliasing of transient resources (on by default). The inspector turns it off so
    // every intermediate port stays readable after the frame; takes effect on the next compile.
    void setAliasing(bool enabled);
    bool aliasing() const { return mAliasing; }

private:
    std::string where(const std::string& pointer) const;
    void allocate(gpu::Context& gpu);

    std::string mName = "graph";
    std::string mDescription;
    std::string mSourceFile;
    std::shared_ptr<JsonSource> mSource;
    std::vector<std::unique_ptr<Pass>> mPasses;
    std::map<std::string, std::string> mPassWhere;  // pass -> JSON pointer
    std::vector<GraphEdge> mEdges;
    std::vector<std::string> mOutputs;

    // Execution state.
    std::optional<CompiledGraph> mCompiled;
    bool mPassesCompiled = false;
    std::vector<std::shared_ptr<void>> mPhysical;  // Image or Buffer per physical index
    std::map<std::string, std::shared_ptr<gpu::Image>> mPersistentTextures;
    std::map<std::string, std::shared_ptr<gpu::Buffer>> mPersistentBuffers;
    std::set<std::string> mFreshHistory;
    std::map<std::string, uint64_t> mUpstreamHash;
    uint64_t mCompileGeneration = 0;
    std::vector<PassTiming> mTimings;
    double mFrameGpuMs = 0.0;
    uint64_t mFrameIndex = 0;
    bool mAliasing = true;
};

}  // namespace loom
