#include "core/shader/ShaderEnums.h"

#include <cctype>
#include <stdexcept>

namespace loom {

std::string upperSnakeCase(const std::string& name) {
    std::string out;
    for (size_t i = 0; i < name.size(); ++i) {
        unsigned char c = name[i];
        bool boundary = i > 0 && std::isupper(c) && !std::isupper((unsigned char)name[i - 1]);
        if (boundary || (i > 0 && std::isdigit(c) && !std::isdigit((unsigned char)name[i - 1])))
            out += '_';
        out += c == '-' || c == ' ' ? '_' : char(std::toupper(c));
    }
    return out;
}

ShaderDefines enumDefines(const std::string& prefix, const std::vector<std::string>& choices) {
    ShaderDefines d;
    for (size_t i = 0; i < choices.size(); ++i)
        d[prefix + "_" + upperSnakeCase(choices[i])] = std::to_string(i) + "u";
    return d;
}

ShaderEnumRegistry& ShaderEnumRegistry::instance() {
    static ShaderEnumRegistry r;
    return r;
}

bool ShaderEnumRegistry::add(ShaderEnum e) {
    for (auto& x : mEnums) {
        if (x.prefix != e.prefix) continue;
        if (x.choices != e.choices)
            throw std::logic_error("shader enum " + e.prefix + " registered twice, differently");
        return true;
    }
    mEnums.push_back(std::move(e));
    return true;
}

const ShaderEnum& ShaderEnumRegistry::get(const std::string& prefix) const {
    for (auto& x : mEnums)
        if (x.prefix == prefix) return x;
    throw std::logic_error("no shader enum " + prefix + " is registered");
}

ShaderDefines ShaderEnumRegistry::defines() const {
    ShaderDefines d;
    for (auto& e : mEnums) d.merge(enumDefines(e.prefix, e.choices));
    return d;
}

// Core enums: the NEE/BSDF MIS heuristic of shaders/lib/mis.glsl.
LOOM_REGISTER_SHADER_ENUM(MisHeuristic, "MIS_HEURISTIC", {"balance", "power"},
                          "MIS heuristic between light and BSDF sampling (Veach 1997)");
// The specular constraint of shaders/lib/manifold (SMS, MNEE and the partitioned variants).
LOOM_REGISTER_SHADER_ENUM(ManifoldConstraint, "MANIFOLD_CONSTRAINT",
                          {"angle_difference", "half_vector"},
                          "specular constraint: angle difference (Zeltner et al. 2020 Sec. 5.1) "
                          "or half vector (Hanika et al. 2015)");
// How a manifold walk controls its Newton step size (shaders/lib/manifold/sms.glsl).
LOOM_REGISTER_SHADER_ENUM(ManifoldStepControl, "MANIFOLD_STEP", {"reprojection", "descent"},
                          "Newton step size: halved when the re-traced chain leaves its shapes "
                          "(Zeltner et al. 2020 reference code), or also when the constraint "
                          "error does not fall");

}  // namespace loom
