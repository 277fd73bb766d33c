#pragma once
// The inspector's window: GLFW, a Vulkan swapchain on the same device (and queue) the graph
// renders on, Dear ImGui's GLFW + Vulkan backends, textured quads for graph textures, and
// read-back of the presented image for --screenshot.
#include <vulkan/vulkan.h>

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "core/gpu/Context.h"
#include "core/image/Image.h"
#include "imgui.h"

struct GLFWwindow;

namespace loom::inspector {

// An RGBA8 image the UI can draw (see Presenter::drawTexture).
struct DisplayTexture {
    std::shared_ptr<gpu::Image> image;
    VkDescriptorSet set = VK_NULL_HANDLE;
    uint32_t width() const { return image ? image->width() : 0; }
    uint32_t height() const { return image ? image->height() : 0; }
};

class Presenter {
public:
    struct Options {
        int width = 1280, height = 800;
        std::string title = "loom-inspector";
    };
    // Opens the window; throws UserError when there is no display (run under xvfb-run).
    explicit Presenter(const Options& options);
    ~Presenter();
    Presenter(const Presenter&) = delete;
    Presenter& operator=(const Presenter&) = delete;

    // What gpu::Context::Options needs so its device can present to this window.
    static std::vector<std::string> instanceExtensions();
    static std::vector<std::string> deviceExtensions();
    static bool presentationSupport(VkInstance instance, VkPhysicalDevice device, uint32_t family);

    // Creates the surface, swapchain, Dear ImGui's backends and the quad pipeline.
    void attach(std::shared_ptr<gpu::Context> gpu);
    GLFWwindow* window() const { return mWindow; }
    bool shouldClose() const;
    // Polls events and starts a Dear ImGui frame.
    void newFrame();
    // Off: the UI ignores the mouse (scripted --frames runs: the pointer of a virtual display
    // would otherwise hover a widget and pop up its tooltip in screenshots).
    void setMouseEnabled(bool enabled) { mMouseEnabled = enabled; }
    // Uploads tightly packed RGBA8 texels, (re)creating the texture at that size.
    void updateTexture(DisplayTexture& texture, uint32_t width, uint32_t height,
                       const uint8_t* rgba);
    // Draws a texture into a draw list (nearest-neighbour: zoomed pixels stay square).
    // Debian's Dear ImGui 1.86 Vulkan backend binds only its font texture, so a draw
    // callback binds ours.
    void drawTexture(ImDrawList* drawList, const DisplayTexture& texture, ImVec2 p0, ImVec2 p1,
                     ImVec2 uv0 = ImVec2(0, 0), ImVec2 uv1 = ImVec2(1, 1));
    // Renders the Dear ImGui frame and presents it; with `capture`, also returns the
    // presented pixels (RGBA, 0..1 display values).
    void render(ImageData* capture = nullptr);

private:
    struct QuadDraw {
        Presenter* self;
        VkDescriptorSet set;
        float rect[4];  // x0, y0, x1, y1 in framebuffer pixels
        float uv[4];
    };
    static void quadCallback(const ImDrawList* list, const ImDrawCmd* cmd);
    void createSwapchain();
    void destroySwapchain();
    void createQuadPipeline();

    GLFWwindow* mWindow = nullptr;
    std::shared_ptr<gpu::Context> mGpu;
    VkDevice mDevice = VK_NULL_HANDLE;
    VkSurfaceKHR mSurface = VK_NULL_HANDLE;
    VkSwapchainKHR mSwapchain = VK_NULL_HANDLE;
    VkSurfaceFormatKHR mFormat{};
    VkPresentModeKHR mPresentMode = VK_PRESENT_MODE_FIFO_KHR;
    VkExtent2D mExtent{};
    VkRenderPass mRenderPass = VK_NULL_HANDLE;
    std::vector<VkImage> mImages;
    std::vector<VkImageView> mViews;
    std::vector<VkFramebuffer> mFramebuffers;
    std::vector<VkSemaphore> mRenderDone;  // per swapchain image (present waits on it)
    VkSemaphore mAcquired = VK_NULL_HANDLE;
    VkFence mFence = VK_NULL_HANDLE;
    VkCommandPool mPool = VK_NULL_HANDLE;
    VkCommandBuffer mCmd = VK_NULL_HANDLE;
    VkDescriptorPool mDescriptorPool = VK_NULL_HANDLE;
    VkSampler mSampler = VK_NULL_HANDLE;
    VkDescriptorSetLayout mQuadSetLayout = VK_NULL_HANDLE;
    VkPipelineLayout mQuadLayout = VK_NULL_HANDLE;
    VkPipeline mQuadPipeline = VK_NULL_HANDLE;
    std::deque<QuadDraw> mQuads;  // this frame's; stable addresses for the callbacks
    bool mImGuiReady = false, mSwapchainDirty = false, mMouseEnabled = true;
};

}  // namespace loom::inspector
