#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vulkan/vulkan.h>

namespace loom::gpu {

// Texel formats a graph resource can have. Names match GLSL image format qualifiers.
enum class Format { RGBA32F, RGBA16F, RG32F, R32F, R32UI, R32I, RGBA8, RGBA32UI };

const char* formatName(Format f);  // "rgba32f", ...
std::optional<Format> parseFormat(const std::string& name);
VkFormat toVkFormat(Format f);
uint32_t bytesPerTexel(Format f);
uint32_t channelCount(Format f);
bool isFloatFormat(Format f);  // false for r32ui/r32i

}  // namespace loom::gpu
