#include "core/graph/Pass.h"
#include "core/shader/ShaderEnums.h"

#include <cmath>
#include <filesystem>

#include "core/util/Log.h"

namespace loom {

const char* paramTypeName(ParamType t) {
    switch (t) {
        case ParamType::Bool: return "bool";
        case ParamType::Int: return "int";
        case ParamType::Float: return "float";
        case ParamType::String: return "string";
        case ParamType::Enum: return "enum";
        case ParamType::Vec2: return "vec2";
        case ParamType::Vec3: return "vec3";
        case ParamType::Vec4: return "vec4";
        case ParamType::Json: return "json";
    }
    return "?";
}

// ---------------------------------------------------------------------------------------------
// PassReflection

PassReflection::PortBuilder PassReflection::addPort(PortDesc port) {
    if (findPort(port.name) || findScratch(port.name))
        throw std::logic_error("duplicate port '" + port.name + "'");
    mPorts.push_back(std::move(port));
    return PortBuilder(mPorts.back());
}

PassReflection::PortBuilder PassReflection::scratchBuffer(const std::string& name) {
    if (findPort(name) || findScratch(name))
        throw std::logic_error("duplicate port or scratch '" + name + "'");
    PortDesc p;
    p.name = name;
    p.isInput = false;
    p.kind = ResourceKind::Buffer;
    mScratch.push_back(std::move(p));
    return PortBuilder(mScratch.back());
}

PassReflection::PortBuilder PassReflection::scratchTexture(const std::string& name, gpu::Format f) {
    if (findPort(name) || findScratch(name))
        throw std::logic_error("duplicate port or scratch '" + name + "'");
    PortDesc p;
    p.name = name;
    p.isInput = false;
    p.kind = ResourceKind::Texture;
    p.format = f;
    mScratch.push_back(std::move(p));
    return PortBuilder(mScratch.back());
}

PassReflection::PortBuilder PassReflection::inputTexture(const std::string& name,
                                                         std::optional<gpu::Format> f) {
    PortDesc p;
    p.name = name;
    p.isInput = true;
    p.kind = ResourceKind::Texture;
    p.format = f;
    return addPort(p);
}

PassReflection::PortBuilder PassReflection::outputTexture(const std::string& name, gpu::Format f) {
    PortDesc p;
    p.name = name;
    p.isInput = false;
    p.kind = ResourceKind::Texture;
    p.format = f;
    return addPort(p);
}

PassReflection::PortBuilder PassReflection::inputBuffer(const std::string& name) {
    PortDesc p;
    p.name = name;
    p.isInput = true;
    p.kind = ResourceKind::Buffer;
    return addPort(p);
}

PassReflection::PortBuilder PassReflection::outputBuffer(const std::string& name) {
    PortDesc p;
    p.name = name;
    p.isInput = false;
    p.kind = ResourceKind::Buffer;
    return addPort(p);
}

PassReflection::ParamBuilder PassReflection::addParam(ParamDesc param) {
    for (auto& p : mParams)
        if (p.name == param.name) throw std::logic_error("duplicate param '" + param.name + "'");
    mParams.push_back(std::move(param));
    return ParamBuilder(mParams.back());
}

PassReflection::ParamBuilder PassReflection::param(const std::string& name, bool def) {
    return addParam({name, ParamType::Bool, def, {}, {}, {}, ""});
}
PassReflection::ParamBuilder PassReflection::param(const std::string& name, int def) {
    return addParam({name, ParamType::Int, def, {}, {}, {}, ""});
}
PassReflection::ParamBuilder PassReflection::param(const std::string& name, double def) {
    return addParam({name, ParamType::Float, def, {}, {}, {}, ""});
}
PassReflection::ParamBuilder PassReflection::param(const std::string& name, const char* def) {
    return addParam({name, ParamType::String, std::string(def), {}, {}, {}, ""});
}
PassReflection::ParamBuilder PassReflection::paramEnum(const std::string& name,
                                                       const std::string& def,
                                                       std::vector<std::string> choices) {
    return addParam({name, ParamType::Enum, def, {}, {}, std::move(choices), ""});
}
PassReflection::ParamBuilder PassReflection::paramEnum(const std::string& name,
                                                       const std::string& def,
                                                       const ShaderEnum& shared) {
    return addParam({name, ParamType::Enum, def, {}, {}, shared.choices, "", shared.prefix});
}
PassReflection::ParamBuilder PassReflection::paramVec(const std::string& name,
                                                      std::vector<double> def) {
    ParamType t = def.size() == 2 ? ParamType::Vec2 : def.size() == 3 ? ParamType::Vec3
                                                                      : ParamType::Vec4;
    return addParam({name, t, json(def), {}, {}, {}, ""});
}
PassReflection::ParamBuilder PassReflection::paramJson(const std::string& name, json def) {
    return addParam({name, ParamType::Json, std::move(def), {}, {}, {}, ""});
}

void PassReflection::persistentTexture(const std::string& name, gpu::Format f, std::string doc) {
    mPersistent.push_back({name, ResourceKind::Texture, f, {}, std::move(doc)});
}
void PassReflection::persistentBuffer(const std::string& name, SizeRule size, std::string doc) {
    mPersistent.push_back({name, ResourceKind::Buffer, gpu::Format::R32UI, size, std::move(doc)});
}

const PortDesc* PassReflection::findPort(const std::string& name) const {
    for (auto& p : mPorts)
        if (p.name == name) return &p;
    return nullptr;
}
const PortDesc* PassReflection::findScratch(const std::string& name) const {
    for (auto& p : mScratch)
        if (p.name == name) return &p;
    return nullptr;
}
const ParamDesc* PassReflection::findParam(const std::string& name) const {
    for (auto& p : mParams)
        if (p.name == name) return &p;
    return nullptr;
}

// ---------------------------------------------------------------------------------------------
// Parameter validation

namespace {
std::string describe(const json& v) {
    std::string s = v.dump();
    if (s.size() > 40) s = s.substr(0, 37) + "...";
    return s + " (" + v.type_name() + ")";
}

void checkRange(const ParamDesc& d, double x) {
    // NaN compares false against every bound, so it is named before the range test.
    if (!std::isfinite(x))
        throw ParamError(fmt::format("parameter '{}' = {} is not a finite number", d.name, x));
    if ((d.min && x < *d.min) || (d.max && x > *d.max)) {
        std::string range = fmt::format("[{}, {}]", d.min ? fmt::format("{}", *d.min) : "-inf",
                                        d.max ? fmt::format("{}", *d.max) : "inf");
        throw ParamError(fmt::format("parameter '{}' = {} is out of range {}", d.name, x, range));
    }
}
}  // namespace

json validateParam(const ParamDesc& d, const json& v) {
    auto wrongType = [&](const char* expected) {
        return ParamError(fmt::format("parameter '{}' expects {}, got {}", d.name, expected,
                                      describe(v)));
    };
    switch (d.type) {
        case ParamType::Bool:
            if (!v.is_boolean()) throw wrongType("a bool (true/false)");
            return v;
        case ParamType::Int: {
            if (v.is_number_integer()) {
                checkRange(d, double(v.get<int64_t>()));
                return json(v.get<int64_t>());
            }
            if (v.is_number_float() && v.get<double>() == std::floor(v.get<double>())) {
                checkRange(d, v.get<double>());
                if (std::abs(v.get<double>()) > 9.0e18)
                    throw ParamError(fmt::format("parameter '{}' = {} does not fit an integer",
                                                 d.name, v.get<double>()));
                return json(int64_t(v.get<double>()));
            }
            throw wrongType("an integer");
        }
        case ParamType::Float:
            if (!v.is_number()) throw wrongType("a number");
            checkRange(d, v.get<double>());
            return json(v.get<double>());
        case ParamType::String:
            if (!v.is_string()) throw wrongType("a string");
            return v;
        case ParamType::Enum: {
            if (!v.is_string()) throw wrongType("a string");
            for (auto& c : d.choices)
                if (c == v.get<std::string>()) return v;
            std::string list;
            for (auto& c : d.choices) list += (list.empty() ? "" : ", ") + c;
            throw ParamError(fmt::format("parameter '{}' = \"{}\" is not one of: {}", d.name,
                                         v.get<std::string>(), list));
        }
        case ParamType::Vec2:
        case ParamType::Vec3:
        case ParamType::Vec4: {
            size_t n = d.type == ParamType::Vec2 ? 2 : d.type == ParamType::Vec3 ? 3 : 4;
            std::string expected = fmt::format("an array of {} numbers", n);
            if (!v.is_array() || v.size() != n) throw wrongType(expected.c_str());
            json out = json::array();
            for (auto& x : v) {
                if (!x.is_number()) throw wrongType(expected.c_str());
                checkRange(d, x.get<double>());
                out.push_back(x.get<double>());
            }
            return out;
        }
        case ParamType::Json: return v;
    }
    return v;
}

// ---------------------------------------------------------------------------------------------
// Pass

PassReflection Pass::reflection() const {
    PassReflection r;
    reflect(r);
    return r;
}

void Pass::initParams() {
    PassReflection r = reflection();
    for (const auto& p : r.params())
        if (!mParams.count(p.name)) mParams[p.name] = p.defaultValue;
    // Drop values of parameters no longer declared (a ComputePass constant was removed).
    std::erase_if(mParams, [&](const auto& kv) { return !r.findParam(kv.first); });
}

void Pass::setParam(const std::string& name, const json& value) {
    PassReflection r = reflection();
    const ParamDesc* d = r.findParam(name);
    if (!d) {
        std::string list;
        for (auto& p : r.params()) list += (list.empty() ? "" : ", ") + p.name;
        throw ParamError(fmt::format("{} '{}' has no parameter '{}'; valid parameters: {}", mType,
                                     mName, name, list.empty() ? "(none)" : list));
    }
    json v = validateParam(*d, value);
    if (mParams[name] != v) {
        json old = mParams[name];
        mParams[name] = v;
        ++mRevision;
        try {
            onParamChanged(name);
        } catch (...) {
            mParams[name] = old;
            throw;
        }
    }
    // A parameter may declare new parameters (ComputePass constants): give them defaults.
    initParams();
}

std::string Pass::resolvePath(const std::string& path) const {
    namespace fs = std::filesystem;
    if (path.empty() || fs::path(path).is_absolute()) return path;
    if (!mBaseDir.empty() && fs::exists(fs::path(mBaseDir) / path))
        return (fs::path(mBaseDir) / path).string();
    return path;
}

json Pass::getParam(const std::string& name) const {
    auto it = mParams.find(name);
    if (it == mParams.end())
        throw ParamError(fmt::format("{} '{}' has no parameter '{}'", mType, mName, name));
    return it->second;
}

// ---------------------------------------------------------------------------------------------
// Registry

PassRegistry& PassRegistry::instance() {
    static PassRegistry registry;
    return registry;
}

bool PassRegistry::add(PassTypeInfo info) {
    std::string type = info.type;
    mTypes[type] = std::move(info);
    return true;
}

const PassTypeInfo* PassRegistry::find(const std::string& type) const {
    auto it = mTypes.find(type);
    return it == mTypes.end() ? nullptr : &it->second;
}

std::vector<std::string> PassRegistry::types() const {
    std::vector<std::string> out;
    for (auto& [k, v] : mTypes) out.push_back(k);
    return out;
}

std::unique_ptr<Pass> PassRegistry::create(const std::string& type, const std::string& name) const {
    const PassTypeInfo* info = find(type);
    if (!info) {
        std::string list;
        for (auto& [k, v] : mTypes) list += (list.empty() ? "" : ", ") + k;
        throw UserError(fmt::format("unknown pass type '{}'; known types: {}", type, list));
    }
    auto pass = info->create();
    pass->mName = name;
    pass->mType = type;
    pass->initParams();
    return pass;
}

}  // namespace loom
