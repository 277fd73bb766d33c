#include "core/gpu/Context.h"

#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom::gpu {

namespace fs = std::filesystem;

namespace {

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS) throw GpuError(fmt::format("Vulkan call failed ({}): {}", int(r), what));
}

const char* deviceTypeName(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_CPU:
            return "cpu";
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
            return "discrete";
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
            return "integrated";
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
            return "virtual";
        default:
            return "other";
    }
}

VkInstance createInstance(bool validation, bool& validationOn,
                          const std::vector<std::string>& extraExtensions = {}) {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "loom";
    app.pEngineName = "loom";
    app.apiVersion = VK_API_VERSION_1_3;

    std::vector<const char*> layers, extensions;
    for (const auto& e : extraExtensions) extensions.push_back(e.c_str());
    validationOn = false;
    if (validation) {
        uint32_t n = 0;
        vkEnumerateInstanceLayerProperties(&n, nullptr);
        std::vector<VkLayerProperties> props(n);
        vkEnumerateInstanceLayerProperties(&n, props.data());
        for (auto& p : props)
            if (std::strcmp(p.layerName, "VK_LAYER_KHRONOS_validation") == 0) validationOn = true;
        if (validationOn) {
            layers.push_back("VK_LAYER_KHRONOS_validation");
            extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
        } else {
            logWarning("validation requested but VK_LAYER_KHRONOS_validation is not installed");
        }
    }
    VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ci.pApplicationInfo = &app;
    ci.enabledLayerCount = uint32_t(layers.size());
    ci.ppEnabledLayerNames = layers.data();
    ci.enabledExtensionCount = uint32_t(extensions.size());
    ci.ppEnabledExtensionNames = extensions.data();
    VkInstance instance = VK_NULL_HANDLE;
    VkResult r = vkCreateInstance(&ci, nullptr, &instance);
    if (r != VK_SUCCESS)
        throw GpuError(fmt::format(
            "cannot create a Vulkan 1.3 instance (VkResult {}); is a Vulkan driver installed? "
            "(apt-get install mesa-vulkan-drivers for lavapipe)",
            int(r)));
    return instance;
}

std::vector<VkPhysicalDevice> physicalDevices(VkInstance instance) {
    uint32_t n = 0;
    vkEnumeratePhysicalDevices(instance, &n, nullptr);
    std::vector<VkPhysicalDevice> devs(n);
    vkEnumeratePhysicalDevices(instance, &n, devs.data());
    return devs;
}

DeviceInfo describe(VkPhysicalDevice pd, uint32_t index) {
    VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    props.pNext = &driver;
    vkGetPhysicalDeviceProperties2(pd, &props);
    DeviceInfo info;
    info.index = index;
    info.name = props.properties.deviceName;
    info.type = deviceTypeName(props.properties.deviceType);
    info.apiVersion = props.properties.apiVersion;
    info.driver = std::string(driver.driverName) + " " + driver.driverInfo;
    return info;
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

}  // namespace

std::string defaultCacheDir() {
    if (const char* d = std::getenv("LOOM_CACHE_DIR"); d && *d) return d;
    if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return std::string(d) + "/loom";
    if (const char* d = std::getenv("HOME"); d && *d) return std::string(d) + "/.cache/loom";
    return "/tmp/loom-cache";
}

// ---------------------------------------------------------------------------------------------
// Resources

Buffer::~Buffer() {
    if (mMapped) vkUnmapMemory(mDevice, mMemory);
    if (mBuffer) vkDestroyBuffer(mDevice, mBuffer, nullptr);
    if (mMemory) vkFreeMemory(mDevice, mMemory, nullptr);
}

Image::~Image() {
    if (mView) vkDestroyImageView(mDevice, mView, nullptr);
    if (mImage) vkDestroyImage(mDevice, mImage, nullptr);
    if (mMemory) vkFreeMemory(mDevice, mMemory, nullptr);
}

ComputePipeline::~ComputePipeline() {
    if (mPipeline) vkDestroyPipeline(mDevice, mPipeline, nullptr);
    if (mLayout) vkDestroyPipelineLayout(mDevice, mLayout, nullptr);
    if (mSetLayout) vkDestroyDescriptorSetLayout(mDevice, mSetLayout, nullptr);
}

Bindings& Bindings::set(const std::string& name, std::shared_ptr<Image> image) {
    mEntries[name] = std::move(image);
    return *this;
}
Bindings& Bindings::set(const std::string& name, std::shared_ptr<Buffer> buffer) {
    mEntries[name] = std::move(buffer);
    return *this;
}

// ---------------------------------------------------------------------------------------------
// Push constants

PushConstants::PushConstants(const ComputePipeline& pipeline) : mPipeline(&pipeline) {
    const auto& pc = pipeline.reflection().pushConstants;
    mBytes.assign(pc ? pc->size : 0, 0);
}

bool PushConstants::has(const std::string& member) const {
    const auto& pc = mPipeline->reflection().pushConstants;
    if (!pc) return false;
    for (const auto& m : pc->members)
        if (m.name == member) return true;
    return false;
}

const ReflectedMember& PushConstants::member(const std::string& name, const char* expectedBase,
                                             uint32_t count) const {
    const auto& pc = mPipeline->reflection().pushConstants;
    if (pc) {
        for (const auto& m : pc->members) {
            if (m.name != name) continue;
            std::string expected = expectedBase;
            if (count > 1) {
                static const char* prefix[] = {"", "i", "u"};
                int p = expected == "int" ? 1 : expected == "uint" ? 2 : 0;
                expected = std::string(prefix[p]) + "vec" + std::to_string(count);
            }
            if (m.type != expected && !(m.type == "bool" && expected == "uint"))
                throw GpuError(
                    fmt::format("shader '{}': push constant '{}' is {} but was set as {}",
                                mPipeline->name(), name, m.type, expected));
            return m;
        }
    }
    throw GpuError(
        fmt::format("shader '{}' has no push constant member '{}'", mPipeline->name(), name));
}

PushConstants& PushConstants::set(const std::string& name, float v) {
    return set(name, &v, 1);
}
PushConstants& PushConstants::set(const std::string& name, int32_t v) {
    return setInts(name, &v, 1);
}
PushConstants& PushConstants::set(const std::string& name, uint32_t v) {
    return setUints(name, &v, 1);
}
PushConstants& PushConstants::set(const std::string& name, const float* v, uint32_t count) {
    const auto& m = member(name, "float", count);
    std::memcpy(mBytes.data() + m.offset, v, 4 * count);
    return *this;
}
PushConstants& PushConstants::setUints(const std::string& name, const uint32_t* v, uint32_t count) {
    const auto& m = member(name, "uint", count);
    std::memcpy(mBytes.data() + m.offset, v, 4 * count);
    return *this;
}
PushConstants& PushConstants::setInts(const std::string& name, const int32_t* v, uint32_t count) {
    const auto& m = member(name, "int", count);
    std::memcpy(mBytes.data() + m.offset, v, 4 * count);
    return *this;
}

// ---------------------------------------------------------------------------------------------
// Command list

CommandList::~CommandList() {
    if (mContext->mHung) return;  // possibly still executing (see Watchdog)
    VkDevice dev = mContext->mDevice;
    for (auto pool : mPools) vkDestroyDescriptorPool(dev, pool, nullptr);
    if (mQueries) vkDestroyQueryPool(dev, mQueries, nullptr);
    if (mCmd) vkFreeCommandBuffers(dev, mContext->mCommandPool, 1, &mCmd);
}

VkDescriptorSet CommandList::allocateSet(VkDescriptorSetLayout layout) {
    VkDevice dev = mContext->mDevice;
    for (int attempt = 0; attempt < 2; ++attempt) {
        if (!mPools.empty()) {
            VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
            ai.descriptorPool = mPools.back();
            ai.descriptorSetCount = 1;
            ai.pSetLayouts = &layout;
            VkDescriptorSet set = VK_NULL_HANDLE;
            if (vkAllocateDescriptorSets(dev, &ai, &set) == VK_SUCCESS) return set;
        }
        // Pool exhausted (or none yet): open a new one.
        VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1024},
                                        {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1024},
                                        {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 256},
                                        {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 256}};
        VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        pci.maxSets = 256;
        pci.poolSizeCount = 4;
        pci.pPoolSizes = sizes;
        VkDescriptorPool pool;
        check(vkCreateDescriptorPool(dev, &pci, nullptr, &pool), "vkCreateDescriptorPool");
        mPools.push_back(pool);
    }
    throw GpuError("cannot allocate a descriptor set");
}

void CommandList::dispatch(const ComputePipeline& pipeline, const Bindings& bindings,
                           const PushConstants* push, uint32_t gx, uint32_t gy, uint32_t gz) {
    const uint32_t* limit = mContext->mMaxWorkGroupCount;
    if (gx > limit[0] || gy > limit[1] || gz > limit[2])
        throw UserError(
            fmt::format("shader '{}': {}x{}x{} workgroups exceed the device's limit of "
                        "{}x{}x{} (maxComputeWorkGroupCount)",
                        pipeline.name(), gx, gy, gz, limit[0], limit[1], limit[2]));
    bind(pipeline, bindings, push);
    if (gx && gy && gz) vkCmdDispatch(mCmd, gx, gy, gz);
}

void CommandList::dispatchIndirect(const ComputePipeline& pipeline, const Bindings& bindings,
                                   const PushConstants* push, const Buffer& args,
                                   VkDeviceSize offset) {
    if (offset % 4 != 0 || offset + 12 > args.size())
        throw GpuError(
            fmt::format("shader '{}': indirect dispatch arguments at byte {} do not "
                        "fit buffer '{}' ({} bytes, 4-byte aligned)",
                        pipeline.name(), offset, args.name(), args.size()));
    bind(pipeline, bindings, push);
    vkCmdDispatchIndirect(mCmd, args.handle(), offset);
}

void CommandList::bind(const ComputePipeline& pipeline, const Bindings& bindings,
                       const PushConstants* push) {
    const auto& refl = pipeline.reflection();
    std::vector<VkWriteDescriptorSet> writes;
    std::vector<VkDescriptorImageInfo> imageInfos;
    std::vector<VkDescriptorBufferInfo> bufferInfos;
    imageInfos.reserve(refl.bindings.size());
    bufferInfos.reserve(refl.bindings.size());
    VkDescriptorSet set = VK_NULL_HANDLE;
    if (!refl.bindings.empty()) set = allocateSet(pipeline.setLayout());

    for (const auto& b : refl.bindings) {
        const Bindings::Resource* res = nullptr;
        for (const std::string& key : {b.name, b.blockName}) {
            auto it = bindings.entries().find(key);
            if (!key.empty() && it != bindings.entries().end()) {
                res = &it->second;
                break;
            }
        }
        if (!res)
            throw GpuError(
                fmt::format("shader '{}': resource '{}' is not bound", pipeline.name(), b.name));
        VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        w.dstSet = set;
        w.dstBinding = b.binding;
        w.descriptorCount = 1;
        if (b.kind == DescriptorKind::StorageImage) {
            auto* img = std::get_if<std::shared_ptr<Image>>(res);
            if (!img || !*img)
                throw GpuError(fmt::format("shader '{}': '{}' is an image but a buffer was bound",
                                           pipeline.name(), b.name));
            imageInfos.push_back({VK_NULL_HANDLE, (*img)->view(), VK_IMAGE_LAYOUT_GENERAL});
            w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
            w.pImageInfo = &imageInfos.back();
            retain(*img);
        } else if (b.kind == DescriptorKind::StorageBuffer ||
                   b.kind == DescriptorKind::UniformBuffer) {
            auto* buf = std::get_if<std::shared_ptr<Buffer>>(res);
            if (!buf || !*buf)
                throw GpuError(fmt::format("shader '{}': '{}' is a buffer but an image was bound",
                                           pipeline.name(), b.name));
            bufferInfos.push_back({(*buf)->handle(), 0, VK_WHOLE_SIZE});
            w.descriptorType = b.kind == DescriptorKind::StorageBuffer
                                   ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
                                   : VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
            w.pBufferInfo = &bufferInfos.back();
            retain(*buf);
        } else {
            throw GpuError(
                fmt::format("shader '{}': binding '{}' has an unsupported type "
                            "(Loom binds storage images and buffers)",
                            pipeline.name(), b.name));
        }
        writes.push_back(w);
    }
    VkDevice dev = mContext->mDevice;
    if (!writes.empty())
        vkUpdateDescriptorSets(dev, uint32_t(writes.size()), writes.data(), 0, nullptr);
    vkCmdBindPipeline(mCmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
    if (set)
        vkCmdBindDescriptorSets(mCmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.layout(), 0, 1, &set,
                                0, nullptr);
    if (refl.pushConstants && refl.pushConstants->size > 0) {
        std::vector<uint8_t> zeros(refl.pushConstants->size, 0);
        const void* data = push ? push->bytes().data() : zeros.data();
        vkCmdPushConstants(mCmd, pipeline.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0,
                           refl.pushConstants->size, data);
    }
}

void CommandList::dispatchThreads(const ComputePipeline& pipeline, const Bindings& bindings,
                                  const PushConstants* push, uint32_t w, uint32_t h, uint32_t d) {
    const auto& ls = pipeline.reflection().localSize;
    // In 64 bits: near 2^32 threads the rounded-up group count would wrap to a small one.
    uint64_t groups[3] = {(uint64_t(w) + ls[0] - 1) / ls[0], (uint64_t(h) + ls[1] - 1) / ls[1],
                          (uint64_t(d) + ls[2] - 1) / ls[2]};
    const uint32_t* limit = mContext->mMaxWorkGroupCount;
    if (groups[0] > limit[0] || groups[1] > limit[1] || groups[2] > limit[2])
        throw UserError(fmt::format(
            "shader '{}': {}x{}x{} threads need {}x{}x{} workgroups of {}x{}x{}, more than the "
            "device's limit of {}x{}x{} (maxComputeWorkGroupCount)",
            pipeline.name(), w, h, d, groups[0], groups[1], groups[2], ls[0], ls[1], ls[2],
            limit[0], limit[1], limit[2]));
    dispatch(pipeline, bindings, push, uint32_t(groups[0]), uint32_t(groups[1]),
             uint32_t(groups[2]));
}

void CommandList::barrier() {
    VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                       VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT |
                       VK_ACCESS_INDIRECT_COMMAND_READ_BIT;
    VkPipelineStageFlags stages =
        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    // Indirect dispatch arguments are read in the draw-indirect stage.
    vkCmdPipelineBarrier(mCmd, stages, stages | VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT, 0, 1, &mb, 0,
                         nullptr, 0, nullptr);
}

void CommandList::clearImage(const Image& image, float value) {
    VkClearColorValue c{};
    if (isFloatFormat(image.format())) {
        c.float32[0] = c.float32[1] = c.float32[2] = c.float32[3] = value;
    } else {
        c.uint32[0] = c.uint32[1] = c.uint32[2] = c.uint32[3] = uint32_t(value);
    }
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(mCmd, image.handle(), VK_IMAGE_LAYOUT_GENERAL, &c, 1, &range);
}

void CommandList::fillBuffer(const Buffer& buffer, uint32_t value) {
    vkCmdFillBuffer(mCmd, buffer.handle(), 0, VK_WHOLE_SIZE, value);
}

void CommandList::copyImage(const Image& src, const Image& dst) {
    VkImageCopy region{};
    region.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.dstSubresource = region.srcSubresource;
    region.extent = {std::min(src.width(), dst.width()), std::min(src.height(), dst.height()), 1};
    vkCmdCopyImage(mCmd, src.handle(), VK_IMAGE_LAYOUT_GENERAL, dst.handle(),
                   VK_IMAGE_LAYOUT_GENERAL, 1, &region);
}

void CommandList::copyBuffer(const Buffer& src, const Buffer& dst, VkDeviceSize bytes) {
    VkBufferCopy region{0, 0, bytes};
    vkCmdCopyBuffer(mCmd, src.handle(), dst.handle(), 1, &region);
}

uint32_t CommandList::timestamp(std::string label) {
    if (!label.empty() && mLabels.size() < kMaxStamps) {
        // One buffer per context, cleared at each submit: submits are serial (submit waits).
        auto& progress = mContext->mProgress;
        if (!progress) progress = mContext->createBuffer(4 * kMaxStamps, "watchdog progress", true);
        vkCmdFillBuffer(mCmd, progress->handle(), 4 * mLabels.size(), 4, 1u);
    }
    mLabels.push_back(std::move(label));
    if (!mContext->mTimestampsSupported) return mQueryCount++;
    if (mQueryCount >= mQueryCapacity) throw GpuError("too many timestamps in one command list");
    vkCmdWriteTimestamp(mCmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, mQueries, mQueryCount);
    return mQueryCount++;
}

// ---------------------------------------------------------------------------------------------
// Context

VKAPI_ATTR VkBool32 VKAPI_CALL Context::debugCallback(
    VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT,
    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    auto* ctx = static_cast<Context*>(user);
    if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
        ++ctx->mValidationErrors;
        logMessage(LogLevel::Error, std::string("[vulkan] ") + data->pMessage);
    } else if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        logMessage(LogLevel::Warning, std::string("[vulkan] ") + data->pMessage);
    }
    return VK_FALSE;
}

std::vector<DeviceInfo> Context::listDevices() {
    bool validationOn = false;
    VkInstance instance = createInstance(false, validationOn);
    std::vector<DeviceInfo> out;
    auto devs = physicalDevices(instance);
    for (uint32_t i = 0; i < devs.size(); ++i) out.push_back(describe(devs[i], i));
    vkDestroyInstance(instance, nullptr);
    return out;
}

std::shared_ptr<Context> Context::create(const Options& options) {
    std::shared_ptr<Context> ctx(new Context());
    ctx->init(options);
    return ctx;
}

void Context::init(const Options& options) {
    bool validation = options.validation;
#ifndef NDEBUG
    validation = true;  // debug builds: validation layers whenever they are installed
#endif
    if (const char* v = std::getenv("LOOM_VALIDATION"); v && std::string(v) == "1")
        validation = true;
    bool validationOn = false;
    mInstance = createInstance(validation, validationOn, options.instanceExtensions);
    if (validationOn) {
        auto createMessenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(mInstance, "vkCreateDebugUtilsMessengerEXT"));
        VkDebugUtilsMessengerCreateInfoEXT mci{
            VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                          VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT;
        mci.pfnUserCallback = &Context::debugCallback;
        mci.pUserData = this;
        if (createMessenger) createMessenger(mInstance, &mci, nullptr, &mMessenger);
    }

    // Device choice: explicit selector, then LOOM_DEVICE, then lavapipe (runs anywhere).
    std::string selector = options.device;
    if (selector.empty())
        if (const char* d = std::getenv("LOOM_DEVICE")) selector = d;
    auto devs = physicalDevices(mInstance);
    if (devs.empty()) throw GpuError("no Vulkan device found (install mesa-vulkan-drivers)");
    // The first queue family with compute (and, for presentation, graphics and the caller's
    // test); -1 when the device has none.
    auto queueFamilyOf = [&](VkPhysicalDevice pd) {
        uint32_t nq = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &nq, nullptr);
        std::vector<VkQueueFamilyProperties> qp(nq);
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &nq, qp.data());
        VkQueueFlags need = VK_QUEUE_COMPUTE_BIT;
        if (options.queueFamilyFilter) need |= VK_QUEUE_GRAPHICS_BIT;
        for (uint32_t i = 0; i < nq; ++i)
            if ((qp[i].queueFlags & need) == need &&
                (!options.queueFamilyFilter || options.queueFamilyFilter(mInstance, pd, i)))
                return int(i);
        return -1;
    };
    std::vector<DeviceInfo> infos;
    for (uint32_t i = 0; i < devs.size(); ++i) infos.push_back(describe(devs[i], i));
    int chosen = -1;
    if (!selector.empty()) {
        bool numeric = std::all_of(selector.begin(), selector.end(), ::isdigit);
        for (uint32_t i = 0; i < infos.size() && chosen < 0; ++i) {
            if (numeric ? std::stoul(selector) == i
                        : lower(infos[i].name).find(lower(selector)) != std::string::npos ||
                              lower(infos[i].type) == lower(selector))
                chosen = int(i);
        }
        if (chosen < 0) {
            std::string list;
            for (auto& i : infos) list += fmt::format("\n  {}: {} ({})", i.index, i.name, i.type);
            throw UserError(
                fmt::format("no Vulkan device matches '{}'; available:{}", selector, list));
        }
    } else {
        for (uint32_t i = 0; i < infos.size() && chosen < 0; ++i)
            if ((infos[i].name.find("llvmpipe") != std::string::npos || infos[i].type == "cpu") &&
                queueFamilyOf(devs[i]) >= 0)
                chosen = int(i);
        for (uint32_t i = 0; i < infos.size() && chosen < 0; ++i)
            if (queueFamilyOf(devs[i]) >= 0) chosen = int(i);
        if (chosen < 0) chosen = 0;  // reported below as "no compute queue"
    }
    mPhysical = devs[chosen];
    mInfo = infos[chosen];
    if (VK_API_VERSION_MINOR(mInfo.apiVersion) < 3 && VK_API_VERSION_MAJOR(mInfo.apiVersion) == 1)
        logWarning("device '{}' reports Vulkan 1.{}; Loom targets 1.3", mInfo.name,
                   VK_API_VERSION_MINOR(mInfo.apiVersion));

    // Compute queue.
    uint32_t nq = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(mPhysical, &nq, nullptr);
    std::vector<VkQueueFamilyProperties> qprops(nq);
    vkGetPhysicalDeviceQueueFamilyProperties(mPhysical, &nq, qprops.data());
    int family = queueFamilyOf(mPhysical);
    if (family < 0)
        throw GpuError("device '" + mInfo.name + "' has no compute queue" +
                       (options.queueFamilyFilter ? " that can also draw and present" : ""));
    mQueueFamily = uint32_t(family);
    mTimestampsSupported = qprops[mQueueFamily].timestampValidBits > 0;

    // Features: enable what the passes use when the device has it.
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    f2.pNext = &f12;
    vkGetPhysicalDeviceFeatures2(mPhysical, &f2);
    VkPhysicalDeviceVulkan12Features want12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    want12.scalarBlockLayout = f12.scalarBlockLayout;
    want12.shaderFloat16 = f12.shaderFloat16;
    want12.storageBuffer8BitAccess = f12.storageBuffer8BitAccess;
    want12.hostQueryReset = f12.hostQueryReset;
    VkPhysicalDeviceFeatures2 want{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    want.pNext = &want12;
    const auto& have = f2.features;
    want.features.shaderStorageImageExtendedFormats = have.shaderStorageImageExtendedFormats;
    want.features.shaderStorageImageReadWithoutFormat = have.shaderStorageImageReadWithoutFormat;
    want.features.shaderStorageImageWriteWithoutFormat = have.shaderStorageImageWriteWithoutFormat;
    want.features.shaderInt64 = have.shaderInt64;
    want.features.shaderFloat64 = have.shaderFloat64;

    float priority = 1.0f;
    VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = mQueueFamily;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;
    VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    dci.pNext = &want;
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    std::vector<const char*> deviceExtensions;
    for (const auto& e : options.deviceExtensions) deviceExtensions.push_back(e.c_str());
    dci.enabledExtensionCount = uint32_t(deviceExtensions.size());
    dci.ppEnabledExtensionNames = deviceExtensions.data();
    check(vkCreateDevice(mPhysical, &dci, nullptr, &mDevice), "vkCreateDevice");
    vkGetDeviceQueue(mDevice, mQueueFamily, 0, &mQueue);

    VkCommandPoolCreateInfo cpci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    cpci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    cpci.queueFamilyIndex = mQueueFamily;
    check(vkCreateCommandPool(mDevice, &cpci, nullptr, &mCommandPool), "vkCreateCommandPool");

    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(mPhysical, &props);
    mTimestampPeriod = props.limits.timestampPeriod;
    for (int i = 0; i < 3; ++i) mMaxWorkGroupCount[i] = props.limits.maxComputeWorkGroupCount[i];
    mMaxImageDimension2D = props.limits.maxImageDimension2D;
    vkGetPhysicalDeviceMemoryProperties(mPhysical, &mMemoryProps);

    // Persisted VkPipelineCache, keyed by the device's pipeline-cache UUID: lavapipe compiles
    // every pipeline with LLVM, so a warm cache makes the second run start fast.
    mCacheDir = options.cacheDir.empty() ? defaultCacheDir() : options.cacheDir;
    std::string uuid;
    for (uint8_t b : props.pipelineCacheUUID) uuid += fmt::format("{:02x}", b);
    mPipelineCachePath = mCacheDir + "/pipelines-" + uuid + ".bin";
    std::vector<char> initial;
    if (std::ifstream in(mPipelineCachePath, std::ios::binary); in)
        initial.assign(std::istreambuf_iterator<char>(in), {});
    VkPipelineCacheCreateInfo pcci{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
    pcci.initialDataSize = initial.size();
    pcci.pInitialData = initial.empty() ? nullptr : initial.data();
    if (vkCreatePipelineCache(mDevice, &pcci, nullptr, &mPipelineCache) != VK_SUCCESS) {
        pcci.initialDataSize = 0;  // stale or corrupt file: start empty
        pcci.pInitialData = nullptr;
        check(vkCreatePipelineCache(mDevice, &pcci, nullptr, &mPipelineCache),
              "vkCreatePipelineCache");
    }
    logDebug("device: {} ({}), driver {}", mInfo.name, mInfo.type, mInfo.driver);
}

Context::~Context() {
    if (mWatchdogThread.joinable()) {
        {
            std::lock_guard<std::mutex> lock(mWatchdogMutex);
            mWatchdogStop = true;
            mWatchdogWake.notify_all();
        }
        mWatchdogThread.join();
    }
    if (mHung) {  // the device may still run the timed-out work: leak instead of hanging
        new std::shared_ptr<Buffer>(std::move(mProgress));
        return;
    }
    if (mDevice) {
        vkDeviceWaitIdle(mDevice);
        mProgress.reset();  // before the device goes
        try {
            savePipelineCache();
        } catch (...) {
        }
        vkDestroyPipelineCache(mDevice, mPipelineCache, nullptr);
        vkDestroyCommandPool(mDevice, mCommandPool, nullptr);
        vkDestroyDevice(mDevice, nullptr);
    }
    if (mMessenger) {
        auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(mInstance, "vkDestroyDebugUtilsMessengerEXT"));
        if (destroy) destroy(mInstance, mMessenger, nullptr);
    }
    if (mInstance) vkDestroyInstance(mInstance, nullptr);
}

void Context::savePipelineCache() {
    size_t size = 0;
    vkGetPipelineCacheData(mDevice, mPipelineCache, &size, nullptr);
    std::vector<char> data(size);
    vkGetPipelineCacheData(mDevice, mPipelineCache, &size, data.data());
    std::error_code ec;
    fs::create_directories(mCacheDir, ec);
    // Write to a temporary then rename so concurrent processes never read a torn file.
    std::string tmp = mPipelineCachePath + ".tmp" + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary);
        if (!out) return;
        out.write(data.data(), std::streamsize(size));
    }
    fs::rename(tmp, mPipelineCachePath, ec);
}

void Context::checkMemory(VkResult r, const char* call, const std::string& name,
                          VkDeviceSize bytes) const {
    // Running out is a request too large for this device (an input error), not a Loom bug.
    if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY)
        throw UserError(fmt::format("'{}': out of {} memory for {:.1f} MiB on {} ({})", name,
                                    r == VK_ERROR_OUT_OF_DEVICE_MEMORY ? "device" : "host",
                                    double(bytes) / (1024.0 * 1024.0), mInfo.name, call));
    check(r, call);
}

uint32_t Context::findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags props) const {
    for (uint32_t i = 0; i < mMemoryProps.memoryTypeCount; ++i)
        if ((typeBits & (1u << i)) && (mMemoryProps.memoryTypes[i].propertyFlags & props) == props)
            return i;
    throw GpuError("no suitable Vulkan memory type");
}

VkDeviceMemory Context::allocate(VkMemoryRequirements req, VkMemoryPropertyFlags props,
                                 const std::string& name) {
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = findMemoryType(req.memoryTypeBits, props);
    VkDeviceMemory mem;
    checkMemory(vkAllocateMemory(mDevice, &ai, nullptr, &mem), "vkAllocateMemory", name, req.size);
    return mem;
}

std::shared_ptr<Buffer> Context::createBuffer(VkDeviceSize size, const std::string& name,
                                              bool hostVisible) {
    auto buf = std::shared_ptr<Buffer>(new Buffer());
    buf->mDevice = mDevice;
    buf->mSize = std::max<VkDeviceSize>(size, 4);
    buf->mName = name;
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = buf->mSize;
    bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT |
                VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT;
    check(vkCreateBuffer(mDevice, &bci, nullptr, &buf->mBuffer), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(mDevice, buf->mBuffer, &req);
    VkMemoryPropertyFlags props =
        hostVisible ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
                    : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
    buf->mMemory = allocate(req, props, name);
    checkMemory(vkBindBufferMemory(mDevice, buf->mBuffer, buf->mMemory, 0), "vkBindBufferMemory",
                name, req.size);
    if (hostVisible)
        check(vkMapMemory(mDevice, buf->mMemory, 0, VK_WHOLE_SIZE, 0, &buf->mMapped),
              "vkMapMemory");
    return buf;
}

std::shared_ptr<Image> Context::createImage(uint32_t width, uint32_t height, Format format,
                                            const std::string& name, VkImageUsageFlags extraUsage) {
    if (width == 0 || height == 0)
        throw GpuError(fmt::format("image '{}' has zero size {}x{}", name, width, height));
    if (width > mMaxImageDimension2D || height > mMaxImageDimension2D)
        throw UserError(
            fmt::format("image '{}' of {}x{} exceeds the device's largest 2D image "
                        "({} texels per side)",
                        name, width, height, mMaxImageDimension2D));
    auto img = std::shared_ptr<Image>(new Image());
    img->mDevice = mDevice;
    img->mWidth = width;
    img->mHeight = height;
    img->mFormat = format;
    img->mName = name;
    VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ici.imageType = VK_IMAGE_TYPE_2D;
    ici.format = toVkFormat(format);
    ici.extent = {width, height, 1};
    ici.mipLevels = 1;
    ici.arrayLayers = 1;
    ici.samples = VK_SAMPLE_COUNT_1_BIT;
    ici.tiling = VK_IMAGE_TILING_OPTIMAL;
    ici.usage = VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                VK_IMAGE_USAGE_TRANSFER_DST_BIT | extraUsage;
    ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    check(vkCreateImage(mDevice, &ici, nullptr, &img->mImage), "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(mDevice, img->mImage, &req);
    img->mMemory = allocate(req, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, name);
    checkMemory(vkBindImageMemory(mDevice, img->mImage, img->mMemory, 0), "vkBindImageMemory", name,
                req.size);
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = img->mImage;
    vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vci.format = ici.format;
    vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    check(vkCreateImageView(mDevice, &vci, nullptr, &img->mView), "vkCreateImageView");

    // Every image lives in GENERAL layout (storage access only); cleared to zero so a
    // pass never reads garbage.
    auto cmd = beginCommands();
    VkImageMemoryBarrier ib{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    ib.srcAccessMask = 0;
    ib.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    ib.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    ib.newLayout = VK_IMAGE_LAYOUT_GENERAL;
    ib.srcQueueFamilyIndex = ib.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    ib.image = img->mImage;
    ib.subresourceRange = vci.subresourceRange;
    vkCmdPipelineBarrier(cmd->handle(), VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                         VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &ib);
    cmd->clearImage(*img, 0.0f);
    submit(*cmd);
    return img;
}

std::shared_ptr<ComputePipeline> Context::createPipeline(const std::vector<uint32_t>& spirv,
                                                         const ShaderReflection& reflection,
                                                         const std::string& name) {
    auto p = std::shared_ptr<ComputePipeline>(new ComputePipeline());
    p->mDevice = mDevice;
    p->mReflection = reflection;
    p->mName = name;
    std::vector<VkDescriptorSetLayoutBinding> lb;
    for (const auto& b : reflection.bindings) {
        if (b.set != 0)
            throw GpuError(fmt::format("shader '{}': binding '{}' uses set {}; Loom uses set 0",
                                       name, b.name, b.set));
        VkDescriptorSetLayoutBinding x{};
        x.binding = b.binding;
        x.descriptorCount = b.arraySize;
        x.stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
        switch (b.kind) {
            case DescriptorKind::StorageImage:
                x.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
                break;
            case DescriptorKind::StorageBuffer:
                x.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
                break;
            case DescriptorKind::UniformBuffer:
                x.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
                break;
            case DescriptorKind::SampledImage:
                x.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
                break;
            default:
                throw GpuError(fmt::format("shader '{}': unsupported binding '{}'", name, b.name));
        }
        lb.push_back(x);
    }
    VkDescriptorSetLayoutCreateInfo dl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dl.bindingCount = uint32_t(lb.size());
    dl.pBindings = lb.data();
    check(vkCreateDescriptorSetLayout(mDevice, &dl, nullptr, &p->mSetLayout),
          "vkCreateDescriptorSetLayout");
    VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0,
                              reflection.pushConstants ? reflection.pushConstants->size : 0};
    VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pl.setLayoutCount = 1;
    pl.pSetLayouts = &p->mSetLayout;
    pl.pushConstantRangeCount = range.size ? 1 : 0;
    pl.pPushConstantRanges = &range;
    check(vkCreatePipelineLayout(mDevice, &pl, nullptr, &p->mLayout), "vkCreatePipelineLayout");

    VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smci.codeSize = spirv.size() * 4;
    smci.pCode = spirv.data();
    VkShaderModule module;
    check(vkCreateShaderModule(mDevice, &smci, nullptr, &module), "vkCreateShaderModule");
    VkComputePipelineCreateInfo cpci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    cpci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    cpci.stage.module = module;
    cpci.stage.pName = "main";
    cpci.layout = p->mLayout;
    VkResult r =
        vkCreateComputePipelines(mDevice, mPipelineCache, 1, &cpci, nullptr, &p->mPipeline);
    vkDestroyShaderModule(mDevice, module, nullptr);
    check(r, "vkCreateComputePipelines");
    return p;
}

std::unique_ptr<CommandList> Context::beginCommands() {
    auto list = std::unique_ptr<CommandList>(new CommandList());
    list->mContext = this;
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = mCommandPool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    check(vkAllocateCommandBuffers(mDevice, &ai, &list->mCmd), "vkAllocateCommandBuffers");
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(vkBeginCommandBuffer(list->mCmd, &bi), "vkBeginCommandBuffer");
    if (mTimestampsSupported) {
        list->mQueryCapacity = 512;
        VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
        qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
        qi.queryCount = list->mQueryCapacity;
        check(vkCreateQueryPool(mDevice, &qi, nullptr, &list->mQueries), "vkCreateQueryPool");
        vkCmdResetQueryPool(list->mCmd, list->mQueries, 0, list->mQueryCapacity);
    }
    return list;
}

namespace {
Watchdog& watchdogState() {
    static Watchdog w;
    return w;
}
}  // namespace

void Context::setWatchdog(Watchdog watchdog) {
    watchdogState() = std::move(watchdog);
}
const Watchdog& Context::watchdog() {
    return watchdogState();
}

std::string Context::describeHang(const CommandList& list) const {
    const Watchdog& dog = watchdog();
    std::string running;
    if (mProgress) {
        const volatile uint32_t* done = static_cast<const uint32_t*>(mProgress->mapped());
        for (size_t i = 0; i < list.mLabels.size() && i < CommandList::kMaxStamps; ++i) {
            if (list.mLabels[i].empty() || done[i] != 0u) continue;
            running = list.mLabels[i] + " was running";
            break;
        }
    }
    if (running.empty())
        for (const auto& l : list.mLabels)
            if (!l.empty()) running += (running.empty() ? "one of " : ", ") + l;
    return fmt::format(
        "GPU watchdog: the device did not finish within {} s{}: a shader that never "
        "terminates, or a frame too large for the timeout (loom render --gpu-timeout S, or "
        "LOOM_GPU_TIMEOUT; 0 waits forever)",
        dog.seconds, running.empty() ? "" : " (" + running + ")");
}

void Context::watchdogLoop() {
    std::unique_lock<std::mutex> lock(mWatchdogMutex);
    while (!mWatchdogStop) {
        if (!mWatchedList) {
            mWatchdogWake.wait(lock);
            continue;
        }
        const uint64_t submit = mWatchedSubmit;
        const Watchdog& dog = watchdog();
        auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration<double>(std::min(dog.seconds, 1e9));
        mWatchdogWake.wait_until(lock, deadline, [&] {
            return mWatchdogStop || !mWatchedList || mWatchedSubmit != submit;
        });
        if (mWatchdogStop || !mWatchedList || mWatchedSubmit != submit) continue;
        mHung = true;
        std::string msg = describeHang(*mWatchedList);
        if (dog.onHang) dog.onHang(msg);  // ends the process
        mWatchedList = nullptr;
    }
}

void Context::submit(CommandList& list) {
    if (mHung) throw GpuHang("the device is still running work that timed out earlier");
    check(vkEndCommandBuffer(list.mCmd), "vkEndCommandBuffer");
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &list.mCmd;
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    check(vkCreateFence(mDevice, &fci, nullptr, &fence), "vkCreateFence");
    if (mProgress) std::memset(mProgress->mapped(), 0, 4 * CommandList::kMaxStamps);
    const Watchdog& dog = watchdog();
    const bool watched = dog.seconds > 0 && dog.onHang;
    if (watched) {
        std::lock_guard<std::mutex> lock(mWatchdogMutex);
        if (!mWatchdogThread.joinable()) mWatchdogThread = std::thread([this] { watchdogLoop(); });
        mWatchedList = &list;
        ++mWatchedSubmit;
        mWatchdogWake.notify_all();
    }
    VkResult r = vkQueueSubmit(mQueue, 1, &si, fence);
    const uint64_t timeoutNs =
        dog.seconds > 0 ? uint64_t(std::min(dog.seconds, 1e9) * 1e9) : UINT64_MAX;
    if (r == VK_SUCCESS) r = vkWaitForFences(mDevice, 1, &fence, VK_TRUE, timeoutNs);
    if (watched) {
        std::lock_guard<std::mutex> lock(mWatchdogMutex);
        mWatchedList = nullptr;
        mWatchdogWake.notify_all();
    }
    if (r == VK_TIMEOUT) {
        mHung = true;  // never wait on, or free, what the device may still be using
        std::string msg = describeHang(list);
        if (dog.onHang) dog.onHang(msg);
        throw GpuHang(msg);
    }
    vkDestroyFence(mDevice, fence, nullptr);
    check(r, "vkQueueSubmit/vkWaitForFences (device lost?)");
    list.mTimestampsNs.assign(list.mQueryCount, 0.0);
    if (mTimestampsSupported && list.mQueryCount > 0) {
        std::vector<uint64_t> ticks(list.mQueryCount);
        vkGetQueryPoolResults(mDevice, list.mQueries, 0, list.mQueryCount,
                              ticks.size() * sizeof(uint64_t), ticks.data(), sizeof(uint64_t),
                              VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
        for (uint32_t i = 0; i < list.mQueryCount; ++i)
            list.mTimestampsNs[i] = double(ticks[i] - ticks[0]) * mTimestampPeriod;
    }
    list.mRetained.clear();
}

void Context::uploadBuffer(const Buffer& buffer, const void* data, size_t bytes, size_t offset) {
    if (bytes == 0) return;
    if (offset + bytes > buffer.size())
        throw GpuError(fmt::format("upload of {} bytes overflows buffer '{}' ({} bytes)", bytes,
                                   buffer.name(), buffer.size()));
    auto staging = createBuffer(bytes, "staging", true);
    std::memcpy(staging->mapped(), data, bytes);
    auto cmd = beginCommands();
    VkBufferCopy region{0, offset, bytes};
    vkCmdCopyBuffer(cmd->handle(), staging->handle(), buffer.handle(), 1, &region);
    submit(*cmd);
}

void Context::downloadBuffer(const Buffer& buffer, void* data, size_t bytes, size_t offset) {
    if (bytes == 0) return;
    if (offset + bytes > buffer.size())
        throw GpuError(
            fmt::format("download of {} bytes overflows buffer '{}'", bytes, buffer.name()));
    auto staging = createBuffer(bytes, "staging", true);
    auto cmd = beginCommands();
    VkBufferCopy region{offset, 0, bytes};
    vkCmdCopyBuffer(cmd->handle(), buffer.handle(), staging->handle(), 1, &region);
    submit(*cmd);
    std::memcpy(data, staging->mapped(), bytes);
}

void Context::uploadImage(const Image& image, const void* texels) {
    auto staging = createBuffer(image.byteSize(), "staging", true);
    std::memcpy(staging->mapped(), texels, image.byteSize());
    auto cmd = beginCommands();
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {image.width(), image.height(), 1};
    vkCmdCopyBufferToImage(cmd->handle(), staging->handle(), image.handle(),
                           VK_IMAGE_LAYOUT_GENERAL, 1, &region);
    submit(*cmd);
}

void Context::uploadImageRows(const Image& image, const void* texels, uint32_t firstRow,
                              uint32_t rows) {
    if (rows == 0) return;
    if (size_t(firstRow) + rows > image.height())
        throw GpuError("uploadImageRows: rows " + std::to_string(firstRow) + ".." +
                       std::to_string(firstRow + rows - 1) + " outside the image's " +
                       std::to_string(image.height()));
    const size_t bytes = image.byteSize() / image.height() * rows;
    auto staging = createBuffer(bytes, "staging", true);
    std::memcpy(staging->mapped(), texels, bytes);
    auto cmd = beginCommands();
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageOffset = {0, int32_t(firstRow), 0};
    region.imageExtent = {image.width(), rows, 1};
    vkCmdCopyBufferToImage(cmd->handle(), staging->handle(), image.handle(),
                           VK_IMAGE_LAYOUT_GENERAL, 1, &region);
    submit(*cmd);
}

void Context::downloadImage(const Image& image, void* texels) {
    auto staging = createBuffer(image.byteSize(), "staging", true);
    auto cmd = beginCommands();
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {image.width(), image.height(), 1};
    vkCmdCopyImageToBuffer(cmd->handle(), image.handle(), VK_IMAGE_LAYOUT_GENERAL,
                           staging->handle(), 1, &region);
    submit(*cmd);
    std::memcpy(texels, staging->mapped(), image.byteSize());
}

}  // namespace loom::gpu
