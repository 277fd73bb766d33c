#include "core/gpu/Format.h"

namespace loom::gpu {

namespace {
struct FormatInfo {
    Format format;
    const char* name;
    VkFormat vk;
    uint32_t bytes;
    uint32_t channels;
    bool isFloat;
};
constexpr FormatInfo kFormats[] = {
    {Format::RGBA32F, "rgba32f", VK_FORMAT_R32G32B32A32_SFLOAT, 16, 4, true},
    {Format::RGBA16F, "rgba16f", VK_FORMAT_R16G16B16A16_SFLOAT, 8, 4, true},
    {Format::RG32F, "rg32f", VK_FORMAT_R32G32_SFLOAT, 8, 2, true},
    {Format::R32F, "r32f", VK_FORMAT_R32_SFLOAT, 4, 1, true},
    {Format::R32UI, "r32ui", VK_FORMAT_R32_UINT, 4, 1, false},
    {Format::R32I, "r32i", VK_FORMAT_R32_SINT, 4, 1, false},
    {Format::RGBA8, "rgba8", VK_FORMAT_R8G8B8A8_UNORM, 4, 4, true},
    {Format::RGBA32UI, "rgba32ui", VK_FORMAT_R32G32B32A32_UINT, 16, 4, false},
};
const FormatInfo& info(Format f) { return kFormats[static_cast<int>(f)]; }
}  // namespace

const char* formatName(Format f) { return info(f).name; }
VkFormat toVkFormat(Format f) { return info(f).vk; }
uint32_t bytesPerTexel(Format f) { return info(f).bytes; }
uint32_t channelCount(Format f) { return info(f).channels; }
bool isFloatFormat(Format f) { return info(f).isFloat; }

std::optional<Format> parseFormat(const std::string& name) {
    for (const auto& fi : kFormats)
        if (name == fi.name) return fi.format;
    return std::nullopt;
}

}  // namespace loom::gpu
