#pragma once
// Vulkan 1.3 compute context: instance, device choice (lavapipe by default), resources,
// compute pipelines bound by reflected name, command recording, timestamps, readback.
#include <vulkan/vulkan.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "core/gpu/Format.h"
#include "core/shader/SpirvReflect.h"

namespace loom::gpu {

struct DeviceInfo {
    uint32_t index = 0;
    std::string name;
    std::string type;  // "cpu", "discrete", "integrated", "virtual", "other"
    uint32_t apiVersion = 0;
    std::string driver;
};

class Context;

class Buffer {
public:
    ~Buffer();
    VkBuffer handle() const { return mBuffer; }
    VkDeviceSize size() const { return mSize; }
    const std::string& name() const { return mName; }
    // Only for host-visible buffers (staging); nullptr otherwise.
    void* mapped() const { return mMapped; }

private:
    friend class Context;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkBuffer mBuffer = VK_NULL_HANDLE;
    VkDeviceMemory mMemory = VK_NULL_HANDLE;
    VkDeviceSize mSize = 0;
    void* mMapped = nullptr;
    std::string mName;
};

class Image {
public:
    ~Image();
    VkImage handle() const { return mImage; }
    VkImageView view() const { return mView; }
    uint32_t width() const { return mWidth; }
    uint32_t height() const { return mHeight; }
    Format format() const { return mFormat; }
    const std::string& name() const { return mName; }
    size_t byteSize() const { return size_t(mWidth) * mHeight * bytesPerTexel(mFormat); }

private:
    friend class Context;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkImage mImage = VK_NULL_HANDLE;
    VkImageView mView = VK_NULL_HANDLE;
    VkDeviceMemory mMemory = VK_NULL_HANDLE;
    uint32_t mWidth = 0, mHeight = 0;
    Format mFormat = Format::RGBA32F;
    std::string mName;
};

class ComputePipeline {
public:
    ~ComputePipeline();
    const ShaderReflection& reflection() const { return mReflection; }
    const std::string& name() const { return mName; }
    VkPipeline handle() const { return mPipeline; }
    VkPipelineLayout layout() const { return mLayout; }
    VkDescriptorSetLayout setLayout() const { return mSetLayout; }

private:
    friend class Context;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkPipeline mPipeline = VK_NULL_HANDLE;
    VkPipelineLayout mLayout = VK_NULL_HANDLE;
    VkDescriptorSetLayout mSetLayout = VK_NULL_HANDLE;
    ShaderReflection mReflection;
    std::string mName;
};

// Resources bound to a dispatch by the names the shader declares (reflected from SPIR-V).
class Bindings {
public:
    using Resource = std::variant<std::shared_ptr<Image>, std::shared_ptr<Buffer>>;
    Bindings& set(const std::string& name, std::shared_ptr<Image> image);
    Bindings& set(const std::string& name, std::shared_ptr<Buffer> buffer);
    const std::map<std::string, Resource>& entries() const { return mEntries; }

private:
    std::map<std::string, Resource> mEntries;
};

// Push-constant block filled by member name, type-checked against the reflection.
class PushConstants {
public:
    explicit PushConstants(const ComputePipeline& pipeline);
    bool has(const std::string& member) const;
    PushConstants& set(const std::string& member, float v);
    PushConstants& set(const std::string& member, int32_t v);
    PushConstants& set(const std::string& member, uint32_t v);
    PushConstants& set(const std::string& member, const float* v, uint32_t count);  // vecN
    PushConstants& setUints(const std::string& member, const uint32_t* v, uint32_t count);
    PushConstants& setInts(const std::string& member, const int32_t* v, uint32_t count);
    const std::vector<uint8_t>& bytes() const { return mBytes; }
    // The whole block at once (KernelParams fills it by reflected member).
    void setBytes(const std::vector<uint8_t>& bytes) {
        size_t n = mBytes.size();
        mBytes = bytes;
        mBytes.resize(n);
    }

private:
    const ReflectedMember& member(const std::string& name, const char* expectedBase,
                                  uint32_t count) const;
    const ComputePipeline* mPipeline;
    std::vector<uint8_t> mBytes;
};

class CommandList {
public:
    ~CommandList();
    VkCommandBuffer handle() const { return mCmd; }
    // Binds by reflected name; throws GpuError naming the missing/mismatched binding.
    void dispatch(const ComputePipeline& pipeline, const Bindings& bindings,
                  const PushConstants* push, uint32_t groupsX, uint32_t groupsY = 1,
                  uint32_t groupsZ = 1);
    // Workgroup counts read on the device from args at offset (three uints, as
    // VkDispatchIndirectCommand): a kernel can size the next dispatch, down to no groups,
    // without a round trip to the host. barrier() makes earlier writes of args visible.
    void dispatchIndirect(const ComputePipeline& pipeline, const Bindings& bindings,
                          const PushConstants* push, const Buffer& args, VkDeviceSize offset = 0);
    // Dispatch enough groups to cover width x height x depth threads.
    void dispatchThreads(const ComputePipeline& pipeline, const Bindings& bindings,
                         const PushConstants* push, uint32_t width, uint32_t height = 1,
                         uint32_t depth = 1);
    // Full compute/transfer memory barrier: passes are serialised with one of these.
    void barrier();
    void clearImage(const Image& image, float value = 0.0f);
    void fillBuffer(const Buffer& buffer, uint32_t value = 0);
    void copyImage(const Image& src, const Image& dst);
    void copyBuffer(const Buffer& src, const Buffer& dst, VkDeviceSize bytes);
    // Returns the timestamp slot index; resolved after Context::submit. The label names the
    // work that ends at this stamp: the watchdog reports the first label not yet reached.
    uint32_t timestamp(std::string label = {});
    // Nanoseconds for each timestamp() slot; valid after submit.
    const std::vector<double>& timestampsNs() const { return mTimestampsNs; }
    // Keep a resource alive until the list completes.
    void retain(std::shared_ptr<void> resource) { mRetained.push_back(std::move(resource)); }

private:
    friend class Context;
    static constexpr uint32_t kMaxStamps = 512;
    Context* mContext = nullptr;
    VkCommandBuffer mCmd = VK_NULL_HANDLE;
    std::vector<VkDescriptorPool> mPools;
    VkQueryPool mQueries = VK_NULL_HANDLE;
    uint32_t mQueryCount = 0;
    uint32_t mQueryCapacity = 0;
    std::vector<double> mTimestampsNs;
    // Labelled stamps also write 1 to their slot of the context's host-visible progress
    // buffer: the watchdog reads it while the work runs, with no Vulkan call (lavapipe blocks
    // query reads meanwhile).
    std::vector<std::string> mLabels;
    std::vector<std::shared_ptr<void>> mRetained;
    VkDescriptorSet allocateSet(VkDescriptorSetLayout layout);
    // Descriptor set, pipeline and push constants of a dispatch.
    void bind(const ComputePipeline& pipeline, const Bindings& bindings, const PushConstants* push);
};

// The GPU watchdog: a submit that has not finished after `seconds` (0 = wait forever) is a hang.
// The device cannot be used after one (the work may still be running), so onHang, given the
// message, ends the process; it is called from a watchdog thread, because some drivers
// (lavapipe) execute inside vkQueueSubmit. Without a handler only the fence wait is bounded:
// submit throws GpuHang and the context skips every further wait.
struct Watchdog {
    double seconds = 0.0;
    std::function<void(const std::string& message)> onHang;
};

class Context {
public:
    // Process-wide: every context's submits use it.
    static void setWatchdog(Watchdog watchdog);
    static const Watchdog& watchdog();
    struct Options {
        std::string device;       // "" = default (LOOM_DEVICE, else lavapipe, else first device)
        bool validation = false;  // also enabled by LOOM_VALIDATION=1
        std::string cacheDir;     // "" = default cache directory (see shaderCacheDir())
        // Presentation (the inspector): extra extensions, and a test the queue family must
        // pass besides compute (e.g. glfwGetPhysicalDevicePresentationSupport). With a test
        // the family must also support graphics, and only devices that have one are chosen.
        std::vector<std::string> instanceExtensions, deviceExtensions;
        std::function<bool(VkInstance, VkPhysicalDevice, uint32_t family)> queueFamilyFilter;
    };
    static std::shared_ptr<Context> create(const Options& options);
    static std::shared_ptr<Context> create() { return create(Options()); }
    static std::vector<DeviceInfo> listDevices();
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    const DeviceInfo& deviceInfo() const { return mInfo; }
    VkDevice device() const { return mDevice; }
    VkPhysicalDevice physicalDevice() const { return mPhysical; }
    VkInstance instance() const { return mInstance; }
    VkQueue queue() const { return mQueue; }
    uint32_t queueFamily() const { return mQueueFamily; }
    VkPipelineCache pipelineCache() const { return mPipelineCache; }
    const std::string& cacheDir() const { return mCacheDir; }
    // Count of validation-layer errors reported so far (tests assert it stays 0).
    uint32_t validationErrors() const { return mValidationErrors; }

    std::shared_ptr<Buffer> createBuffer(VkDeviceSize size, const std::string& name,
                                         bool hostVisible = false);
    // Images are storage + transfer images in GENERAL layout; extraUsage adds e.g. SAMPLED
    // (the inspector samples its display images).
    std::shared_ptr<Image> createImage(uint32_t width, uint32_t height, Format format,
                                       const std::string& name, VkImageUsageFlags extraUsage = 0);
    std::shared_ptr<ComputePipeline> createPipeline(const std::vector<uint32_t>& spirv,
                                                    const ShaderReflection& reflection,
                                                    const std::string& name);

    std::unique_ptr<CommandList> beginCommands();
    // Submits and waits; afterwards timestamps are resolved.
    void submit(CommandList& list);

    void uploadBuffer(const Buffer& buffer, const void* data, size_t bytes, size_t offset = 0);
    void downloadBuffer(const Buffer& buffer, void* data, size_t bytes, size_t offset = 0);
    // Texels tightly packed in the image's format.
    void uploadImage(const Image& image, const void* texels);
    // Rows firstRow .. firstRow + rows - 1 only; texels holds those rows, tightly packed.
    void uploadImageRows(const Image& image, const void* texels, uint32_t firstRow, uint32_t rows);
    void downloadImage(const Image& image, void* texels);

    void savePipelineCache();

private:
    Context() = default;
    void init(const Options& options);
    uint32_t findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags props) const;
    // Out of memory is a UserError naming `name` and the size.
    void checkMemory(VkResult r, const char* call, const std::string& name,
                     VkDeviceSize bytes) const;
    VkDeviceMemory allocate(VkMemoryRequirements req, VkMemoryPropertyFlags props,
                            const std::string& name);
    friend class CommandList;
    static VKAPI_ATTR VkBool32 VKAPI_CALL debugCallback(
        VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT types,
        const VkDebugUtilsMessengerCallbackDataEXT* data, void* user);

    VkInstance mInstance = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT mMessenger = VK_NULL_HANDLE;
    VkPhysicalDevice mPhysical = VK_NULL_HANDLE;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkQueue mQueue = VK_NULL_HANDLE;
    uint32_t mQueueFamily = 0;
    VkCommandPool mCommandPool = VK_NULL_HANDLE;
    VkPipelineCache mPipelineCache = VK_NULL_HANDLE;
    VkPhysicalDeviceMemoryProperties mMemoryProps{};
    double mTimestampPeriod = 1.0;
    uint32_t mMaxWorkGroupCount[3] = {65535, 65535, 65535};
    uint32_t mMaxImageDimension2D = 16384;
    bool mTimestampsSupported = true;
    DeviceInfo mInfo;
    std::string mCacheDir;
    std::string mPipelineCachePath;
    uint32_t mValidationErrors = 0;
    std::atomic<bool> mHung{false};  // a submit timed out: the device may still be running it
    // "pass 'x' (Type) was running": the first labelled stamp of `list` not yet written.
    std::string describeHang(const CommandList& list) const;
    // The watchdog thread, started at the first submit that needs it.
    std::thread mWatchdogThread;
    std::mutex mWatchdogMutex;
    std::condition_variable mWatchdogWake;
    const CommandList* mWatchedList = nullptr;  // armed while a submit runs
    uint64_t mWatchedSubmit = 0;
    bool mWatchdogStop = false;
    std::shared_ptr<Buffer> mProgress;  // CommandList::timestamp(label) slots, one per stamp
    void watchdogLoop();
};

// Default on-disk cache directory: $LOOM_CACHE_DIR, else $XDG_CACHE_HOME/loom, else
// ~/.cache/loom, else /tmp/loom-cache.
std::string defaultCacheDir();

}  // namespace loom::gpu
