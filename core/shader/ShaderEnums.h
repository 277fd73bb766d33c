#pragma once
// Enumerations shared by C++ parameter declarations and GLSL, declared once in C++. Every
// kernel is compiled with `<PREFIX>_<CHOICE>` defines (upper snake case) equal to each choice's
// index, so GLSL names the values and never restates them. A pass parameter declared over a
// registered enum (PassReflection::paramEnum(name, def, shaderEnum("PREFIX"))) reaches the GPU
// as that index. Enums of one pass only are generated per pass (KernelParams.h) instead.
#include <string>
#include <vector>

#include "core/shader/ShaderCompiler.h"

namespace loom {

struct ShaderEnum {
    std::string prefix;                // e.g. "MIS_HEURISTIC"
    std::vector<std::string> choices;  // e.g. {"balance", "power"}: MIS_HEURISTIC_BALANCE = 0
    std::string doc;
};

// "misHeuristic" -> "MIS_HEURISTIC", "defensivePairwise" -> "DEFENSIVE_PAIRWISE".
std::string upperSnakeCase(const std::string& name);
// {PREFIX_CHOICE: index} for each choice.
ShaderDefines enumDefines(const std::string& prefix, const std::vector<std::string>& choices);

class ShaderEnumRegistry {
public:
    static ShaderEnumRegistry& instance();
    // Throws std::logic_error when the prefix is taken by a different enum.
    bool add(ShaderEnum e);
    // Throws std::logic_error naming the unknown prefix (a programming error, not user input).
    const ShaderEnum& get(const std::string& prefix) const;
    const std::vector<ShaderEnum>& all() const { return mEnums; }
    // The defines of every registered enum (added to every compile by ShaderCompiler).
    ShaderDefines defines() const;

private:
    std::vector<ShaderEnum> mEnums;
};

inline const ShaderEnum& shaderEnum(const std::string& prefix) {
    return ShaderEnumRegistry::instance().get(prefix);
}

#define LOOM_REGISTER_SHADER_ENUM(Id, Prefix, ...) \
    static const bool s_shader_enum_##Id =         \
        ::loom::ShaderEnumRegistry::instance().add({Prefix, __VA_ARGS__})

}  // namespace loom
