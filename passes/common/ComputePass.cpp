// ComputePass: a pass declared entirely in JSON (shader, port -> GLSL bindings, push-constant
// parameters with types and defaults, dispatch size). New algorithm stages need no C++.
#include <algorithm>
#include <cmath>
#include <set>

#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"

namespace loom {

namespace {

struct PortDef {
    std::string port, glsl;
    PortDesc desc;
};
struct ConstantDef {
    std::string name, glslType;  // float, int, uint, bool, vec2..4
    ParamDesc desc;
};

std::string str(const json& j, const char* key, const std::string& def = "") {
    if (!j.contains(key)) return def;
    if (!j[key].is_string()) throw ParamError(std::string("'") + key + "' must be a string");
    return j[key];
}

void checkKeys(const json& j, std::initializer_list<const char*> valid, const std::string& what) {
    for (auto& [k, v] : j.items()) {
        bool ok = false;
        for (const char* x : valid) ok |= k == x;
        if (!ok) {
            std::string list;
            for (const char* x : valid) list += (list.empty() ? "" : ", ") + std::string(x);
            throw ParamError(what + ": unknown field '" + k + "'; valid fields: " + list);
        }
    }
}

PortDef parsePort(const std::string& name, const json& j, bool isInput, bool persistent) {
    std::string what = (persistent ? "persistent '" : isInput ? "input '" : "output '") + name + "'";
    if (!j.is_object()) throw ParamError(what + " must be an object");
    checkKeys(j,
              {"glsl", "kind", "format", "optional", "previousFrame", "inPlaceOf", "doc", "scale",
               "size", "bytes", "bytesPerPixel"},
              what);
    PortDef d;
    d.port = name;
    d.glsl = str(j, "glsl", name);
    d.desc.name = name;
    d.desc.isInput = isInput;
    std::string kind = str(j, "kind", "texture");
    if (kind != "texture" && kind != "buffer")
        throw ParamError(what + ": kind must be \"texture\" or \"buffer\", got \"" + kind + "\"");
    d.desc.kind = kind == "texture" ? ResourceKind::Texture : ResourceKind::Buffer;
    std::string fmtName = str(j, "format", isInput ? "any" : "rgba32f");
    if (fmtName != "any") {
        auto f = gpu::parseFormat(fmtName);
        if (!f)
            throw ParamError(what + ": unknown format '" + fmtName +
                             "'; valid: rgba32f, rgba16f, rg32f, r32f, r32ui, r32i, rgba8");
        d.desc.format = *f;
    } else if (!isInput) {
        throw ParamError(what + ": an output needs a concrete format");
    }
    if (j.contains("optional")) {
        if (!j["optional"].is_boolean()) throw ParamError(what + ": 'optional' must be a bool");
        d.desc.optional = j["optional"];
    }
    if (j.contains("previousFrame")) {
        // A temporal feedback input: the connected output's value at the end of the last frame.
        if (!j["previousFrame"].is_boolean())
            throw ParamError(what + ": 'previousFrame' must be a bool");
        if (!isInput && j["previousFrame"].get<bool>())
            throw ParamError(what + ": 'previousFrame' applies to inputs only");
        d.desc.previousFrame = j["previousFrame"];
    }
    if (j.contains("inPlaceOf")) {
        // Read-modify-write: this output is the resource of the named input (the graph checks
        // that it is an input of matching kind, format and size).
        if (isInput || persistent) throw ParamError(what + ": 'inPlaceOf' applies to outputs only");
        d.desc.inPlaceOf = str(j, "inPlaceOf");
        if (d.desc.inPlaceOf.empty()) throw ParamError(what + ": 'inPlaceOf' names an input port");
    }
    d.desc.doc = str(j, "doc");
    if (j.contains("scale")) {
        if (!j["scale"].is_number() || j["scale"].get<double>() <= 0)
            throw ParamError(what + ": 'scale' must be a positive number");
        d.desc.size.scale = j["scale"].get<float>();
    }
    if (j.contains("size")) {
        const json& s = j["size"];
        if (!s.is_array() || s.size() != 2 || !s[0].is_number_unsigned() ||
            !s[1].is_number_unsigned() || s[0] == 0 || s[1] == 0)
            throw ParamError(what + ": 'size' must be [width, height] (positive integers)");
        d.desc.size.mode = SizeRule::Mode::Fixed;
        d.desc.size.width = s[0];
        d.desc.size.height = s[1];
    }
    if (d.desc.kind == ResourceKind::Buffer && !isInput) {
        if (j.contains("bytes")) {
            if (!j["bytes"].is_number_unsigned()) throw ParamError(what + ": 'bytes' must be >= 0");
            d.desc.size.mode = SizeRule::Mode::Fixed;
            d.desc.size.bytes = j["bytes"];
        } else if (j.contains("bytesPerPixel")) {
            if (!j["bytesPerPixel"].is_number_unsigned())
                throw ParamError(what + ": 'bytesPerPixel' must be >= 0");
            d.desc.size.bytesPerPixel = j["bytesPerPixel"];
        } else {
            throw ParamError(what + ": a buffer output needs 'bytes' or 'bytesPerPixel'");
        }
    }
    return d;
}

ConstantDef parseConstant(const std::string& name, const json& j) {
    std::string what = "constant '" + name + "'";
    if (!j.is_object()) throw ParamError(what + " must be an object with 'type' and 'default'");
    checkKeys(j, {"type", "default", "min", "max", "doc"}, what);
    ConstantDef c;
    c.name = name;
    c.glslType = str(j, "type", "float");
    c.desc.name = name;
    c.desc.doc = str(j, "doc");
    const std::string& t = c.glslType;
    if (t == "float") c.desc.type = ParamType::Float;
    else if (t == "int") c.desc.type = ParamType::Int;
    else if (t == "uint") {
        c.desc.type = ParamType::Int;
        c.desc.min = 0;
    } else if (t == "bool") c.desc.type = ParamType::Bool;
    else if (t == "vec2") c.desc.type = ParamType::Vec2;
    else if (t == "vec3") c.desc.type = ParamType::Vec3;
    else if (t == "vec4") c.desc.type = ParamType::Vec4;
    else
        throw ParamError(what + ": unknown type '" + t +
                         "'; valid: float, int, uint, bool, vec2, vec3, vec4");
    if (j.contains("min")) c.desc.min = j["min"].get<double>();
    if (j.contains("max")) c.desc.max = j["max"].get<double>();
    if (!j.contains("default")) {
        json zero = c.desc.type == ParamType::Bool ? json(false)
                    : c.desc.type == ParamType::Vec2 ? json({0.0, 0.0})
                    : c.desc.type == ParamType::Vec3 ? json({0.0, 0.0, 0.0})
                    : c.desc.type == ParamType::Vec4 ? json({0.0, 0.0, 0.0, 0.0})
                                                     : json(0);
        c.desc.defaultValue = validateParam(c.desc, zero);
    } else {
        c.desc.defaultValue = validateParam(c.desc, j["default"]);
    }
    return c;
}

const std::set<std::string> kFixedParams = {"shader",    "inputs",  "outputs", "persistent",
                                            "constants", "defines", "dispatch"};

std::string upper(std::string s) {
    for (auto& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
    return s;
}

}  // namespace

class ComputePass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        for (const auto& p : mInputs) r.addPort(p.desc);
        for (const auto& p : mOutputs) r.addPort(p.desc);
        for (const auto& p : mPersistent) {
            if (p.desc.kind == ResourceKind::Texture)
                r.persistentTexture(p.port, p.desc.format.value_or(gpu::Format::RGBA32F),
                                    p.desc.doc);
            else
                r.persistentBuffer(p.port, p.desc.size, p.desc.doc);
        }
        r.param("shader", "").doc("GLSL compute shader (relative to the graph, or search paths)");
        r.paramJson("inputs", json::object())
            .doc("{port: {glsl, kind: texture|buffer, format|any, optional, previousFrame, doc}}");
        r.paramJson("outputs", json::object())
            .doc(
                "{port: {glsl, kind, format, scale | size:[w,h] | bytes | bytesPerPixel, "
                "inPlaceOf: input, doc}}");
        r.paramJson("persistent", json::object())
            .doc("history resources that survive frames: {name: {glsl, kind, format, ...}}");
        r.paramJson("constants", json::object())
            .doc("push-constant parameters: {name: {type, default, min, max, doc}}");
        r.paramJson("defines", json::object()).doc("preprocessor defines {NAME: value}");
        r.paramJson("dispatch", "frame")
            .doc("threads: \"frame\", an output port name, or [x, y, z]");
        for (const auto& c : mConstants) r.addParam(c.desc);
    }

    bool paramChangesPorts(const std::string& name) const override {
        return kFixedParams.count(name) > 0;
    }

    void onParamChanged(const std::string& name) override {
        if (!kFixedParams.count(name)) return;
        mPipelines.clear();
        const json v = getParam(name);
        auto parseMap = [&](const char* what, auto fn) {
            if (!v.is_object()) throw ParamError(std::string("'") + what + "' must be an object");
            for (auto& [k, x] : v.items()) fn(k, x);
        };
        // Port lists are built on copies and committed only once valid: a rejected value must
        // leave the declared ports as they were (Pass::setParam restores the parameter).
        std::vector<PortDef> inputs = mInputs, outputs = mOutputs, persistent = mPersistent;
        if (name == "inputs") {
            inputs.clear();
            parseMap("inputs",
                     [&](auto& k, auto& x) { inputs.push_back(parsePort(k, x, true, false)); });
        } else if (name == "outputs") {
            outputs.clear();
            parseMap("outputs",
                     [&](auto& k, auto& x) { outputs.push_back(parsePort(k, x, false, false)); });
        } else if (name == "persistent") {
            persistent.clear();
            parseMap("persistent",
                     [&](auto& k, auto& x) { persistent.push_back(parsePort(k, x, false, true)); });
        } else if (name == "constants") {
            std::vector<ConstantDef> defs;
            parseMap("constants", [&](auto& k, auto& x) {
                if (kFixedParams.count(k))
                    throw ParamError("constant '" + k + "' clashes with a ComputePass parameter");
                defs.push_back(parseConstant(k, x));
            });
            mConstants = defs;
        } else if (name == "defines") {
            parseMap("defines", [&](auto& k, auto& x) {
                if (!x.is_string() && !x.is_number() && !x.is_boolean())
                    throw ParamError("define '" + k + "' must be a string, number or bool");
            });
        } else if (name == "dispatch") {
            bool ok = v.is_string() || (v.is_array() && v.size() >= 1 && v.size() <= 3 &&
                                        std::all_of(v.begin(), v.end(), [](auto& x) {
                                            return x.is_number_unsigned() && x > 0 &&
                                                   x <= 0xffffffffu;
                                        }));
            if (!ok)
                throw ParamError("'dispatch' must be \"frame\", an output port name, or [x, y, z] "
                                 "with each count in 1..4294967295");
        }
        // Port names must be unique across inputs, outputs and persistent resources.
        std::set<std::string> seen;
        for (auto* list : {&inputs, &outputs, &persistent})
            for (auto& p : *list)
                if (!seen.insert(p.port).second)
                    throw ParamError("port name '" + p.port + "' is declared twice");
        mInputs = std::move(inputs);
        mOutputs = std::move(outputs);
        mPersistent = std::move(persistent);
    }

    void compile(ShaderLibrary& shaders) override {
        mPipelines.clear();
        if (param<std::string>("shader").empty()) throw UserError("parameter 'shader' is empty");
        // Compile once with every optional port present to check the declaration against the
        // shader's reflected interface.
        ShaderDefines defines = baseDefines();
        for (auto& p : mInputs) defines["HAS_" + upper(p.port)] = "1";
        for (auto& p : mOutputs) defines["HAS_" + upper(p.port)] = "1";
        auto pipeline = shaders.pipeline(shaderPath(shaders), defines);
        checkInterface(*pipeline);
    }

    void execute(ExecuteContext& ctx) override {
        ShaderDefines defines = baseDefines();
        for (auto& p : mInputs) defines["HAS_" + upper(p.port)] = ctx.has(p.port) ? "1" : "0";
        for (auto& p : mOutputs) defines["HAS_" + upper(p.port)] = ctx.has(p.port) ? "1" : "0";
        std::string key;
        for (auto& [k, v] : defines) key += k + "=" + v + ";";
        auto& pipeline = mPipelines[key];
        if (!pipeline) {
            pipeline = compileKernel(*this, ctx.shaders(), shaderPath(ctx.shaders()), defines);
            checkInterface(*pipeline);
        }

        gpu::Bindings b;
        // Kernels may include lib/scene.glsl & co.: bind the scene when one is loaded.
        if (ctx.hasScene()) ctx.scene().bind(b);
        for (auto* list : {&mInputs, &mOutputs}) {
            for (auto& p : *list) {
                if (!ctx.has(p.port)) continue;
                if (p.desc.kind == ResourceKind::Texture) b.set(p.glsl, ctx.texture(p.port));
                else b.set(p.glsl, ctx.buffer(p.port));
            }
        }
        for (auto& p : mPersistent) {
            if (p.desc.kind == ResourceKind::Texture) b.set(p.glsl, ctx.persistentTexture(p.port));
            else b.set(p.glsl, ctx.persistentBuffer(p.port));
        }

        // Standard members, then the declared constants, by name (KernelParams.h).
        KernelParams params(*this, *pipeline, ctx);

        // Dispatch size.
        uint32_t threads[3] = {ctx.width(), ctx.height(), 1};
        json d = getParam("dispatch");
        if (d.is_array()) {
            for (size_t i = 0; i < 3; ++i) threads[i] = i < d.size() ? d[i].get<uint32_t>() : 1;
        } else if (d != "frame") {
            std::string port = d;
            if (auto t = ctx.texture(port)) {
                threads[0] = t->width();
                threads[1] = t->height();
            } else if (auto buf = ctx.buffer(port)) {
                threads[0] = uint32_t(buf->size() / 4);
                threads[1] = 1;
            } else {
                throw UserError("'dispatch' names port '" + port + "', which has no resource");
            }
        }
        params.dispatch(ctx, b, threads[0], threads[1], threads[2]);
    }

private:
    ShaderDefines baseDefines() const {
        ShaderDefines d;
        const json defines = getParam("defines");
        for (auto& [k, v] : defines.items())
            d[k] = v.is_string() ? v.get<std::string>()
                   : v.is_boolean() ? (v.get<bool>() ? "1" : "0")
                                    : v.dump();
        return d;
    }
    std::string shaderPath(ShaderLibrary& shaders) const {
        std::string s = param<std::string>("shader");
        return shaders.compiler().resolve(s, baseDir());
    }
    void checkInterface(const gpu::ComputePipeline& pipeline) const {
        const auto& refl = pipeline.reflection();
        auto declared = [&] {
            std::string list;
            for (auto& b : refl.bindings) list += (list.empty() ? "" : ", ") + b.name;
            return list.empty() ? "(none)" : list;
        };
        for (auto* list : {&mOutputs, &mPersistent}) {
            for (auto& p : *list) {
                const ReflectedBinding* rb = refl.find(p.glsl);
                if (!rb) {
                    if (p.desc.optional) continue;
                    throw UserError("port '" + p.port + "': the shader declares no resource '" +
                                    p.glsl + "'; it declares: " + declared());
                }
                bool isImage = rb->kind == DescriptorKind::StorageImage;
                if (isImage != (p.desc.kind == ResourceKind::Texture))
                    throw UserError("port '" + p.port + "' is declared a " +
                                    (isImage ? "buffer" : "texture") + " but '" + p.glsl +
                                    "' in the shader is a" + (isImage ? "n image" : " buffer"));
                if (isImage && p.desc.format && rb->imageFormat != "unknown" &&
                    rb->imageFormat != gpu::formatName(*p.desc.format))
                    throw UserError("port '" + p.port + "' is " +
                                    gpu::formatName(*p.desc.format) + " but the shader declares '" +
                                    p.glsl + "' as " + rb->imageFormat);
            }
        }
        std::vector<const ReflectedMember*> members;
        if (refl.pushConstants)
            for (auto& x : refl.pushConstants->members) members.push_back(&x);
        if (const ReflectedBinding* ub = refl.find(KernelParams::kUniformBlock))
            for (auto& x : ub->members) members.push_back(&x);
        for (auto& c : mConstants) {
            const ReflectedMember* m = nullptr;
            for (auto* x : members)
                if (x->name == c.name) m = x;
            if (!m)
                throw UserError("constant '" + c.name +
                                "' is not a member of the shader's push_constant block or of "
                                "its uniform block PassParams");
            bool ok = m->type == c.glslType || (c.glslType == "bool" && m->type == "uint");
            if (!ok)
                throw UserError("constant '" + c.name + "' is declared " + c.glslType +
                                " but the shader's push constant is " + m->type);
        }
    }

    std::vector<PortDef> mInputs, mOutputs, mPersistent;
    std::vector<ConstantDef> mConstants;
    std::map<std::string, std::shared_ptr<gpu::ComputePipeline>> mPipelines;
};

LOOM_REGISTER_PASS(ComputePass, "ComputePass",
                   "A compute shader stage declared entirely in JSON (no recompile)");

}  // namespace loom
