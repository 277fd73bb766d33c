#pragma once
// The pass contract: one reflect() declares ports, parameters and persistent state; from that
// declaration come graph validation, `loom passes`, Lua set/get, the inspector's widgets and
// the JSON round trip. Passes register themselves with LOOM_REGISTER_PASS in their own file.
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/gpu/Context.h"
#include "core/shader/ShaderCompiler.h"
#include "core/shader/ShaderEnums.h"
#include "core/util/JsonSource.h"

namespace loom {

enum class ResourceKind { Texture, Buffer };

// How big a resource is. Textures: frame size (optionally scaled) or fixed. Buffers: a byte
// count that is fixed or per frame pixel.
struct SizeRule {
    enum class Mode { Frame, Fixed } mode = Mode::Frame;
    float scale = 1.0f;                 // Frame mode, textures
    uint32_t width = 0, height = 0;     // Fixed mode, textures
    uint64_t bytes = 0;                 // Fixed mode, buffers
    uint64_t bytesPerPixel = 0;         // Frame mode, buffers
    uint64_t extraBytes = 0;            // Frame mode, buffers: header bytes
};

struct PortDesc {
    std::string name;
    bool isInput = true;
    ResourceKind kind = ResourceKind::Texture;
    std::optional<gpu::Format> format;  // textures; nullopt on an input = any format
    SizeRule size;
    bool optional = false;
    // Input only: reads the value the connected output had at the end of the previous frame
    // (a temporal feedback edge: exempt from cycle checks and ordering; the graph keeps a
    // history copy; ExecuteContext::historyReset() is true while that copy is not valid yet).
    bool previousFrame = false;
    // Output only: the name of an input of the same pass whose resource this output reuses
    // (read-modify-write, Granite's storage outputs). The output is the very GPU resource
    // connected to that input; kind, format and size must match it. Other readers of that
    // resource run before this pass. Empty: the output gets a resource of its own.
    std::string inPlaceOf;
    std::string doc;
};

enum class ParamType { Bool, Int, Float, String, Enum, Vec2, Vec3, Vec4, Json };
const char* paramTypeName(ParamType t);

struct ParamDesc {
    std::string name;
    ParamType type = ParamType::Float;
    json defaultValue;
    std::optional<double> min, max;     // numeric (per component for vectors)
    std::vector<std::string> choices;   // Enum
    std::string doc;
    // Enum over a registered ShaderEnum: its define prefix (every kernel has the defines);
    // "" = this pass's own enum, whose `<PARAM>_<CHOICE>` defines only its kernels get.
    std::string shaderEnum;
};

struct PersistentDesc {
    std::string name;
    ResourceKind kind = ResourceKind::Texture;
    gpu::Format format = gpu::Format::RGBA32F;
    SizeRule size;
    std::string doc;
};

// Fluent builder filled by Pass::reflect().
class PassReflection {
public:
    class PortBuilder {
    public:
        PortBuilder(PortDesc& p) : mPort(p) {}
        PortBuilder& doc(std::string d) { mPort.doc = std::move(d); return *this; }
        PortBuilder& optional(bool o = true) { mPort.optional = o; return *this; }
        PortBuilder& format(gpu::Format f) { mPort.format = f; return *this; }
        PortBuilder& anyFormat() { mPort.format.reset(); return *this; }
        PortBuilder& previousFrame(bool p = true) { mPort.previousFrame = p; return *this; }
        // Outputs: reuse the memory of input `input` (see PortDesc::inPlaceOf).
        PortBuilder& inPlaceOf(std::string input) {
            mPort.inPlaceOf = std::move(input);
            return *this;
        }
        PortBuilder& scale(float s) { mPort.size.scale = s; return *this; }
        PortBuilder& fixedSize(uint32_t w, uint32_t h) {
            mPort.size.mode = SizeRule::Mode::Fixed;
            mPort.size.width = w;
            mPort.size.height = h;
            return *this;
        }
        PortBuilder& bytes(uint64_t b) {
            mPort.size.mode = SizeRule::Mode::Fixed;
            mPort.size.bytes = b;
            return *this;
        }
        PortBuilder& bytesPerPixel(uint64_t b, uint64_t extra = 0) {
            mPort.size.mode = SizeRule::Mode::Frame;
            mPort.size.bytesPerPixel = b;
            mPort.size.extraBytes = extra;
            return *this;
        }

    private:
        PortDesc& mPort;
    };
    class ParamBuilder {
    public:
        ParamBuilder(ParamDesc& p) : mParam(p) {}
        ParamBuilder& doc(std::string d) { mParam.doc = std::move(d); return *this; }
        ParamBuilder& range(double lo, double hi) {
            mParam.min = lo;
            mParam.max = hi;
            return *this;
        }
        ParamBuilder& min(double lo) { mParam.min = lo; return *this; }

    private:
        ParamDesc& mParam;
    };

    PortBuilder inputTexture(const std::string& name, std::optional<gpu::Format> f = {});
    PortBuilder outputTexture(const std::string& name, gpu::Format f = gpu::Format::RGBA32F);
    PortBuilder inputBuffer(const std::string& name);
    PortBuilder outputBuffer(const std::string& name);
    PortBuilder addPort(PortDesc port);
    // Scratch resources: memory a pass needs only while its execute() runs (ping-pong between
    // rounds, temporaries). The graph creates them, shows them in the memory report and may
    // alias them with other transient resources, since nothing survives the pass. Size them
    // with the returned builder (bytes / bytesPerPixel for buffers, scale / fixedSize for
    // textures); read them with ExecuteContext::scratchBuffer() / scratchTexture(). Names
    // share the namespace of the pass's ports.
    PortBuilder scratchBuffer(const std::string& name);
    PortBuilder scratchTexture(const std::string& name, gpu::Format f = gpu::Format::RGBA32F);

    ParamBuilder param(const std::string& name, bool def);
    ParamBuilder param(const std::string& name, int def);
    ParamBuilder param(const std::string& name, double def);
    ParamBuilder param(const std::string& name, const char* def);
    ParamBuilder paramEnum(const std::string& name, const std::string& def,
                           std::vector<std::string> choices);
    ParamBuilder paramEnum(const std::string& name, const std::string& def,
                           const ShaderEnum& shared);
    ParamBuilder paramVec(const std::string& name, std::vector<double> def);
    ParamBuilder paramJson(const std::string& name, json def);
    ParamBuilder addParam(ParamDesc param);

    void persistentTexture(const std::string& name, gpu::Format f, std::string doc = "");
    void persistentBuffer(const std::string& name, SizeRule size, std::string doc = "");

    const std::vector<PortDesc>& ports() const { return mPorts; }
    const std::vector<ParamDesc>& params() const { return mParams; }
    const std::vector<PersistentDesc>& persistent() const { return mPersistent; }
    const std::vector<PortDesc>& scratch() const { return mScratch; }
    const PortDesc* findPort(const std::string& name) const;
    const PortDesc* findScratch(const std::string& name) const;
    const ParamDesc* findParam(const std::string& name) const;

private:
    std::vector<PortDesc> mPorts;
    std::vector<ParamDesc> mParams;
    std::vector<PersistentDesc> mPersistent;
    std::vector<PortDesc> mScratch;  // isInput = false
};

class ShaderLibrary;
class ExecuteContext;

// Thrown by parameter validation; the graph adds file/line/node.
class ParamError : public UserError {
public:
    using UserError::UserError;
};

// Checks a value against a declaration and normalises it (int -> float, etc.).
json validateParam(const ParamDesc& desc, const json& value);

class Pass {
public:
    virtual ~Pass() = default;

    // Declare ports, parameters and persistent resources. May depend on parameter values
    // (ComputePass declares its ports from its JSON definition).
    virtual void reflect(PassReflection& r) const = 0;
    // Create pipelines; called after the graph compiled and after shader reloads.
    virtual void compile(ShaderLibrary& shaders) {}
    // Record this frame's work.
    virtual void execute(ExecuteContext& ctx) = 0;
    // After the frame's GPU work finished: read back statistics.
    virtual void frameCompleted(gpu::Context& gpu) {}
    // Scalar results a pass exposes (error values, counters).
    virtual std::map<std::string, double> stats() const { return {}; }
    // Parameters whose change alters the pass's ports need a graph recompile.
    virtual bool paramChangesPorts(const std::string& name) const { return false; }
    // Called after a parameter changed; may throw ParamError (e.g. a missing file).
    virtual void onParamChanged(const std::string& name) {}

    // Directory relative paths in parameters are resolved against (the graph file's).
    void setBaseDir(std::string dir) { mBaseDir = std::move(dir); }
    const std::string& baseDir() const { return mBaseDir; }
    // Absolute path for a parameter path: as is if absolute, else relative to baseDir() when
    // that file exists, else relative to the working directory.
    std::string resolvePath(const std::string& path) const;

    const std::string& name() const { return mName; }
    const std::string& type() const { return mType; }

    // Parameters: validated against reflect(); unknown names list the valid ones.
    void setParam(const std::string& name, const json& value);
    json getParam(const std::string& name) const;
    const std::map<std::string, json>& params() const { return mParams; }
    // Bumped on every parameter change; Accumulate resets when an upstream revision changes.
    uint64_t revision() const { return mRevision; }
    PassReflection reflection() const;

    template <class T>
    T param(const std::string& name) const {
        return getParam(name).get<T>();
    }

protected:
    // Called by the registry after construction to fill defaults.
    friend class PassRegistry;
    void initParams();

private:
    std::string mName, mType, mBaseDir;
    std::map<std::string, json> mParams;
    uint64_t mRevision = 0;
};

struct PassTypeInfo {
    std::string type;
    std::string doc;
    std::function<std::unique_ptr<Pass>()> create;
};

class PassRegistry {
public:
    static PassRegistry& instance();
    bool add(PassTypeInfo info);
    const PassTypeInfo* find(const std::string& type) const;
    std::vector<std::string> types() const;
    // Throws UserError listing the known types.
    std::unique_ptr<Pass> create(const std::string& type, const std::string& name) const;

private:
    std::map<std::string, PassTypeInfo> mTypes;
};

#define LOOM_REGISTER_PASS(Class, TypeName, Doc)                                      \
    static const bool s_registered_##Class = ::loom::PassRegistry::instance().add( \
        {TypeName, Doc, [] { return std::unique_ptr<::loom::Pass>(new Class()); }})

}  // namespace loom
