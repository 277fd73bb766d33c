#pragma once

// Minimal SPIR-V reflection for compute shaders: descriptor bindings, push-constant
// layout and workgroup size. Parses the word stream directly (no third-party code).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace loom {

enum class DescriptorKind {
    StorageImage,
    SampledImage,  // combined image sampler
    UniformBuffer,
    StorageBuffer,
    Sampler,
    Unknown
};

struct ReflectedMember {
    std::string name;
    uint32_t offset = 0;
    uint32_t size = 0;
    // "float","int","uint","bool","vec2","vec3","vec4","ivec2","ivec3","ivec4",
    // "uvec2","uvec3","uvec4","mat4","other"
    std::string type;
};

struct ReflectedBinding {
    std::string name;       // instance (variable) name if non-empty, else the block/type name
    std::string blockName;  // struct type name for buffer blocks ("" otherwise)
    uint32_t set = 0, binding = 0;
    DescriptorKind kind = DescriptorKind::Unknown;
    uint32_t arraySize = 1;  // product of array dimensions; 0 for runtime-sized arrays
    bool readonly = false;   // NonWritable decoration on variable or all members
    // Storage images only: "rgba32f","rgba16f","r32f","r32ui","rg32f","rgba8","r32i","rg16f",
    // "unknown"; empty for every other kind.
    std::string imageFormat;
    // Buffer blocks: the members (uniform blocks are filled like push constants), and for a
    // block that ends in a runtime array, the byte offset of that array and its element stride
    // (what a buffer's declared header and per-element sizes are checked against).
    std::vector<ReflectedMember> members;
    uint32_t blockSize = 0;  // max(offset + size) over sized members
    uint32_t runtimeArrayOffset = 0, runtimeArrayStride = 0;  // stride 0: no runtime array
};


struct ReflectedPushConstants {
    std::string blockName;
    uint32_t size = 0;  // max(offset + size) over members
    std::vector<ReflectedMember> members;
};

struct ShaderReflection {
    std::vector<ReflectedBinding> bindings;  // sorted by (set, binding)
    std::optional<ReflectedPushConstants> pushConstants;
    uint32_t localSize[3] = {1, 1, 1};

    // Matches a binding's name first, then its blockName; nullptr if none.
    const ReflectedBinding* find(std::string_view name) const;
};

const char* toString(DescriptorKind kind);

// Throws std::runtime_error with a clear message on malformed input (bad magic, truncated).
ShaderReflection reflectSpirv(const std::vector<uint32_t>& words);

}  // namespace loom
