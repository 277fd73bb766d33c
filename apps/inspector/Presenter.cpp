#include "apps/inspector/Presenter.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>

#include <algorithm>
#include <cfloat>
#include <cstring>

#include "core/util/Error.h"
#include "core/util/Log.h"
#include "imgui_impl_glfw.h"
#include "imgui_impl_vulkan.h"

namespace loom::inspector {

namespace {

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS) throw GpuError(fmt::format("Vulkan call failed ({}): {}", int(r), what));
}

void checkImGui(VkResult r) {
    if (r != VK_SUCCESS)
        logMessage(LogLevel::Error, fmt::format("Dear ImGui Vulkan backend: VkResult {}", int(r)));
}

// The quad shaders: a rectangle in framebuffer pixels, sampled with nearest filtering.
const char* kQuadVert = R"(#version 450
layout(push_constant) uniform Quad { vec4 rect; vec4 uv; vec2 viewport; } quad;
layout(location = 0) out vec2 outUv;
void main() {
    vec2 corner = vec2(gl_VertexIndex & 1, gl_VertexIndex >> 1);
    vec2 pixel = mix(quad.rect.xy, quad.rect.zw, corner);
    outUv = mix(quad.uv.xy, quad.uv.zw, corner);
    gl_Position = vec4(pixel / quad.viewport * 2.0 - 1.0, 0.0, 1.0);
}
)";
const char* kQuadFrag = R"(#version 450
layout(set = 0, binding = 0) uniform sampler2D image;
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 color;
void main() { color = vec4(texture(image, uv).rgb, 1.0); }
)";

std::vector<uint32_t> compileGlsl(EShLanguage stage, const char* source) {
    static const bool initialised = glslang::InitializeProcess();
    (void)initialised;
    glslang::TShader shader(stage);
    shader.setStrings(&source, 1);
    shader.setEnvInput(glslang::EShSourceGlsl, stage, glslang::EShClientVulkan, 100);
    shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_0);
    shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_0);
    auto messages = EShMessages(EShMsgSpvRules | EShMsgVulkanRules);
    if (!shader.parse(GetDefaultResources(), 450, false, messages))
        throw std::runtime_error(std::string("inspector quad shader: ") + shader.getInfoLog());
    glslang::TProgram program;
    program.addShader(&shader);
    if (!program.link(messages))
        throw std::runtime_error(std::string("inspector quad shader: ") + program.getInfoLog());
    std::vector<uint32_t> spirv;
    glslang::GlslangToSpv(*program.getIntermediate(stage), spirv);
    return spirv;
}

VkShaderModule shaderModule(VkDevice device, const std::vector<uint32_t>& spirv) {
    VkShaderModuleCreateInfo ci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    ci.codeSize = spirv.size() * 4;
    ci.pCode = spirv.data();
    VkShaderModule m;
    check(vkCreateShaderModule(device, &ci, nullptr, &m), "vkCreateShaderModule");
    return m;
}

void glfwErrorCallback(int code, const char* text) {
    logDebug("GLFW error {}: {}", code, text);
}

}  // namespace

Presenter::Presenter(const Options& options) {
    glfwSetErrorCallback(glfwErrorCallback);
    if (!glfwInit())
        throw UserError("cannot open a window: no display (set DISPLAY, or run under xvfb-run -a)");
    if (!glfwVulkanSupported()) {
        glfwTerminate();
        throw UserError("GLFW finds no Vulkan loader for windows (install libvulkan1)");
    }
    glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
    mWindow =
        glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
    if (!mWindow) {
        glfwTerminate();
        throw UserError("cannot create a window");
    }
}

Presenter::~Presenter() {
    if (mDevice) {
        vkDeviceWaitIdle(mDevice);
        if (mImGuiReady) {
            ImGui_ImplVulkan_Shutdown();
            ImGui_ImplGlfw_Shutdown();
            ImGui::DestroyContext();
        }
        destroySwapchain();
        if (mQuadPipeline) vkDestroyPipeline(mDevice, mQuadPipeline, nullptr);
        if (mQuadLayout) vkDestroyPipelineLayout(mDevice, mQuadLayout, nullptr);
        if (mQuadSetLayout) vkDestroyDescriptorSetLayout(mDevice, mQuadSetLayout, nullptr);
        if (mSampler) vkDestroySampler(mDevice, mSampler, nullptr);
        if (mDescriptorPool) vkDestroyDescriptorPool(mDevice, mDescriptorPool, nullptr);
        if (mRenderPass) vkDestroyRenderPass(mDevice, mRenderPass, nullptr);
        if (mCmd) vkFreeCommandBuffers(mDevice, mPool, 1, &mCmd);
        if (mPool) vkDestroyCommandPool(mDevice, mPool, nullptr);
        if (mFence) vkDestroyFence(mDevice, mFence, nullptr);
        if (mAcquired) vkDestroySemaphore(mDevice, mAcquired, nullptr);
    }
    if (mSurface) vkDestroySurfaceKHR(mGpu->instance(), mSurface, nullptr);
    if (mWindow) glfwDestroyWindow(mWindow);
    glfwTerminate();
}

std::vector<std::string> Presenter::instanceExtensions() {
    uint32_t n = 0;
    const char** names = glfwGetRequiredInstanceExtensions(&n);
    return std::vector<std::string>(names, names + n);
}

std::vector<std::string> Presenter::deviceExtensions() {
    return {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
}

bool Presenter::presentationSupport(VkInstance instance, VkPhysicalDevice device, uint32_t family) {
    return glfwGetPhysicalDevicePresentationSupport(instance, device, family) == GLFW_TRUE;
}

bool Presenter::shouldClose() const {
    return glfwWindowShouldClose(mWindow);
}

void Presenter::attach(std::shared_ptr<gpu::Context> gpu) {
    mGpu = std::move(gpu);
    mDevice = mGpu->device();
    check(glfwCreateWindowSurface(mGpu->instance(), mWindow, nullptr, &mSurface),
          "glfwCreateWindowSurface");
    VkBool32 supported = VK_FALSE;
    vkGetPhysicalDeviceSurfaceSupportKHR(mGpu->physicalDevice(), mGpu->queueFamily(), mSurface,
                                         &supported);
    if (!supported)
        throw GpuError("device '" + mGpu->deviceInfo().name + "' cannot present to this window");

    // Surface format: 8-bit UNORM (Dear ImGui's colours are already display values).
    uint32_t n = 0;
    vkGetPhysicalDeviceSurfaceFormatsKHR(mGpu->physicalDevice(), mSurface, &n, nullptr);
    std::vector<VkSurfaceFormatKHR> formats(n);
    vkGetPhysicalDeviceSurfaceFormatsKHR(mGpu->physicalDevice(), mSurface, &n, formats.data());
    if (formats.empty()) throw GpuError("the window surface has no formats");
    mFormat = formats[0];
    for (const auto& f : formats)
        if (f.format == VK_FORMAT_B8G8R8A8_UNORM || f.format == VK_FORMAT_R8G8B8A8_UNORM) {
            mFormat = f;
            break;
        }
    // Present mode: never wait for a (possibly virtual) vblank; the CPU renderer is the limit.
    vkGetPhysicalDeviceSurfacePresentModesKHR(mGpu->physicalDevice(), mSurface, &n, nullptr);
    std::vector<VkPresentModeKHR> modes(n);
    vkGetPhysicalDeviceSurfacePresentModesKHR(mGpu->physicalDevice(), mSurface, &n, modes.data());
    mPresentMode = VK_PRESENT_MODE_FIFO_KHR;
    for (auto want : {VK_PRESENT_MODE_IMMEDIATE_KHR, VK_PRESENT_MODE_MAILBOX_KHR})
        if (std::find(modes.begin(), modes.end(), want) != modes.end()) {
            mPresentMode = want;
            break;
        }

    VkAttachmentDescription color{};
    color.format = mFormat.format;
    color.samples = VK_SAMPLE_COUNT_1_BIT;
    color.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    color.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    color.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    color.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    color.finalLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
    VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub{};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &ref;
    VkSubpassDependency dep{};
    dep.srcSubpass = VK_SUBPASS_EXTERNAL;
    dep.dstSubpass = 0;
    dep.srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    dep.dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    dep.dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
    VkRenderPassCreateInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    rp.attachmentCount = 1;
    rp.pAttachments = &color;
    rp.subpassCount = 1;
    rp.pSubpasses = &sub;
    rp.dependencyCount = 1;
    rp.pDependencies = &dep;
    check(vkCreateRenderPass(mDevice, &rp, nullptr, &mRenderPass), "vkCreateRenderPass");

    VkCommandPoolCreateInfo cp{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    cp.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    cp.queueFamilyIndex = mGpu->queueFamily();
    check(vkCreateCommandPool(mDevice, &cp, nullptr, &mPool), "vkCreateCommandPool");
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = mPool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    check(vkAllocateCommandBuffers(mDevice, &ai, &mCmd), "vkAllocateCommandBuffers");
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(vkCreateFence(mDevice, &fci, nullptr, &mFence), "vkCreateFence");
    VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    check(vkCreateSemaphore(mDevice, &sci, nullptr, &mAcquired), "vkCreateSemaphore");

    VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 64}};
    VkDescriptorPoolCreateInfo dp{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dp.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
    dp.maxSets = 64;
    dp.poolSizeCount = 1;
    dp.pPoolSizes = sizes;
    check(vkCreateDescriptorPool(mDevice, &dp, nullptr, &mDescriptorPool),
          "vkCreateDescriptorPool");

    createSwapchain();
    createQuadPipeline();

    // Dear ImGui.
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // the same layout every start (and in screenshots)
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForVulkan(mWindow, true);
    ImGui_ImplVulkan_InitInfo info{};
    info.Instance = mGpu->instance();
    info.PhysicalDevice = mGpu->physicalDevice();
    info.Device = mDevice;
    info.QueueFamily = mGpu->queueFamily();
    info.Queue = mGpu->queue();
    info.PipelineCache = mGpu->pipelineCache();
    info.DescriptorPool = mDescriptorPool;
    info.MinImageCount = std::max<uint32_t>(2, uint32_t(mImages.size()));
    info.ImageCount = std::max<uint32_t>(2, uint32_t(mImages.size()));
    info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
    info.CheckVkResultFn = checkImGui;
    ImGui_ImplVulkan_Init(&info, mRenderPass);
    mImGuiReady = true;
    auto cmd = mGpu->beginCommands();
    ImGui_ImplVulkan_CreateFontsTexture(cmd->handle());
    mGpu->submit(*cmd);
    ImGui_ImplVulkan_DestroyFontUploadObjects();
}

void Presenter::createSwapchain() {
    VkSurfaceCapabilitiesKHR caps;
    check(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(mGpu->physicalDevice(), mSurface, &caps),
          "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
    int w = 0, h = 0;
    glfwGetFramebufferSize(mWindow, &w, &h);
    mExtent = caps.currentExtent;
    if (mExtent.width == UINT32_MAX) {
        mExtent.width =
            std::clamp(uint32_t(w), caps.minImageExtent.width, caps.maxImageExtent.width);
        mExtent.height =
            std::clamp(uint32_t(h), caps.minImageExtent.height, caps.maxImageExtent.height);
    }
    uint32_t count = std::max(caps.minImageCount + 1, 2u);
    if (caps.maxImageCount) count = std::min(count, caps.maxImageCount);
    // Screenshots copy from the presented image.
    if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT))
        throw GpuError("the window surface cannot be read back (no TRANSFER_SRC usage)");

    VkSwapchainCreateInfoKHR sci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
    sci.surface = mSurface;
    sci.minImageCount = count;
    sci.imageFormat = mFormat.format;
    sci.imageColorSpace = mFormat.colorSpace;
    sci.imageExtent = mExtent;
    sci.imageArrayLayers = 1;
    sci.imageUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    sci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
    sci.preTransform = caps.currentTransform;
    sci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
    if (!(caps.supportedCompositeAlpha & VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR))
        sci.compositeAlpha = VK_COMPOSITE_ALPHA_INHERIT_BIT_KHR;
    sci.presentMode = mPresentMode;
    sci.clipped = VK_TRUE;
    sci.oldSwapchain = VK_NULL_HANDLE;
    check(vkCreateSwapchainKHR(mDevice, &sci, nullptr, &mSwapchain), "vkCreateSwapchainKHR");

    uint32_t n = 0;
    vkGetSwapchainImagesKHR(mDevice, mSwapchain, &n, nullptr);
    mImages.resize(n);
    vkGetSwapchainImagesKHR(mDevice, mSwapchain, &n, mImages.data());
    VkSemaphoreCreateInfo semci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    for (VkImage image : mImages) {
        VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        vci.image = image;
        vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
        vci.format = mFormat.format;
        vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        VkImageView view;
        check(vkCreateImageView(mDevice, &vci, nullptr, &view), "vkCreateImageView");
        mViews.push_back(view);
        VkFramebufferCreateInfo fci{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
        fci.renderPass = mRenderPass;
        fci.attachmentCount = 1;
        fci.pAttachments = &view;
        fci.width = mExtent.width;
        fci.height = mExtent.height;
        fci.layers = 1;
        VkFramebuffer fb;
        check(vkCreateFramebuffer(mDevice, &fci, nullptr, &fb), "vkCreateFramebuffer");
        mFramebuffers.push_back(fb);
        VkSemaphore done;
        check(vkCreateSemaphore(mDevice, &semci, nullptr, &done), "vkCreateSemaphore");
        mRenderDone.push_back(done);
    }
    mSwapchainDirty = false;
}

void Presenter::destroySwapchain() {
    for (auto fb : mFramebuffers) vkDestroyFramebuffer(mDevice, fb, nullptr);
    for (auto v : mViews) vkDestroyImageView(mDevice, v, nullptr);
    for (auto s : mRenderDone) vkDestroySemaphore(mDevice, s, nullptr);
    mFramebuffers.clear();
    mViews.clear();
    mRenderDone.clear();
    mImages.clear();
    if (mSwapchain) vkDestroySwapchainKHR(mDevice, mSwapchain, nullptr);
    mSwapchain = VK_NULL_HANDLE;
}

void Presenter::createQuadPipeline() {
    VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    sci.magFilter = VK_FILTER_NEAREST;
    sci.minFilter = VK_FILTER_LINEAR;  // shrinking: average rather than alias
    sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    sci.maxLod = 0.0f;
    check(vkCreateSampler(mDevice, &sci, nullptr, &mSampler), "vkCreateSampler");

    VkDescriptorSetLayoutBinding b{};
    b.binding = 0;
    b.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    b.descriptorCount = 1;
    b.stageFlags = VK_SHADER_STAGE_FRAGMENT_BIT;
    b.pImmutableSamplers = &mSampler;
    VkDescriptorSetLayoutCreateInfo dl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dl.bindingCount = 1;
    dl.pBindings = &b;
    check(vkCreateDescriptorSetLayout(mDevice, &dl, nullptr, &mQuadSetLayout),
          "vkCreateDescriptorSetLayout");
    VkPushConstantRange range{VK_SHADER_STAGE_VERTEX_BIT, 0, 10 * sizeof(float)};
    VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pl.setLayoutCount = 1;
    pl.pSetLayouts = &mQuadSetLayout;
    pl.pushConstantRangeCount = 1;
    pl.pPushConstantRanges = &range;
    check(vkCreatePipelineLayout(mDevice, &pl, nullptr, &mQuadLayout), "vkCreatePipelineLayout");

    VkShaderModule vs = shaderModule(mDevice, compileGlsl(EShLangVertex, kQuadVert));
    VkShaderModule fs = shaderModule(mDevice, compileGlsl(EShLangFragment, kQuadFrag));
    VkPipelineShaderStageCreateInfo stages[2] = {
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
        {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = vs;
    stages[0].pName = "main";
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = fs;
    stages[1].pName = "main";
    VkPipelineVertexInputStateCreateInfo vi{
        VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo ia{
        VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_STRIP;
    VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    vp.viewportCount = 1;
    vp.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo rs{
        VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    rs.polygonMode = VK_POLYGON_MODE_FILL;
    rs.cullMode = VK_CULL_MODE_NONE;
    rs.lineWidth = 1.0f;
    VkPipelineMultisampleStateCreateInfo ms{
        VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineColorBlendAttachmentState blend{};
    blend.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                           VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
    VkPipelineColorBlendStateCreateInfo cb{
        VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    cb.attachmentCount = 1;
    cb.pAttachments = &blend;
    VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    ds.dynamicStateCount = 2;
    ds.pDynamicStates = dyn;
    VkGraphicsPipelineCreateInfo gp{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    gp.stageCount = 2;
    gp.pStages = stages;
    gp.pVertexInputState = &vi;
    gp.pInputAssemblyState = &ia;
    gp.pViewportState = &vp;
    gp.pRasterizationState = &rs;
    gp.pMultisampleState = &ms;
    gp.pColorBlendState = &cb;
    gp.pDynamicState = &ds;
    gp.layout = mQuadLayout;
    gp.renderPass = mRenderPass;
    VkResult r =
        vkCreateGraphicsPipelines(mDevice, mGpu->pipelineCache(), 1, &gp, nullptr, &mQuadPipeline);
    vkDestroyShaderModule(mDevice, vs, nullptr);
    vkDestroyShaderModule(mDevice, fs, nullptr);
    check(r, "vkCreateGraphicsPipelines");
}

void Presenter::newFrame() {
    glfwPollEvents();
    int w = 0, h = 0;
    glfwGetFramebufferSize(mWindow, &w, &h);
    if (w > 0 && h > 0 && (uint32_t(w) != mExtent.width || uint32_t(h) != mExtent.height))
        mSwapchainDirty = true;
    mQuads.clear();
    ImGui_ImplVulkan_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    if (!mMouseEnabled) ImGui::GetIO().MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
    ImGui::NewFrame();
}

void Presenter::updateTexture(DisplayTexture& tex, uint32_t width, uint32_t height,
                              const uint8_t* rgba) {
    if (!tex.image || tex.image->width() != width || tex.image->height() != height) {
        tex.image = mGpu->createImage(width, height, gpu::Format::RGBA8, "inspector.display",
                                      VK_IMAGE_USAGE_SAMPLED_BIT);
        if (!tex.set) {
            VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
            ai.descriptorPool = mDescriptorPool;
            ai.descriptorSetCount = 1;
            ai.pSetLayouts = &mQuadSetLayout;
            check(vkAllocateDescriptorSets(mDevice, &ai, &tex.set), "vkAllocateDescriptorSets");
        }
        // Loom images stay in GENERAL layout, which sampling accepts.
        VkDescriptorImageInfo ii{VK_NULL_HANDLE, tex.image->view(), VK_IMAGE_LAYOUT_GENERAL};
        VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        w.dstSet = tex.set;
        w.dstBinding = 0;
        w.descriptorCount = 1;
        w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        w.pImageInfo = &ii;
        vkUpdateDescriptorSets(mDevice, 1, &w, 0, nullptr);
    }
    mGpu->uploadImage(*tex.image, rgba);
}

void Presenter::drawTexture(ImDrawList* drawList, const DisplayTexture& tex, ImVec2 p0, ImVec2 p1,
                            ImVec2 uv0, ImVec2 uv1) {
    if (!tex.image || !tex.set) return;
    ImVec2 origin = ImGui::GetMainViewport()->Pos;
    mQuads.push_back({this,
                      tex.set,
                      {p0.x - origin.x, p0.y - origin.y, p1.x - origin.x, p1.y - origin.y},
                      {uv0.x, uv0.y, uv1.x, uv1.y}});
    drawList->AddCallback(&Presenter::quadCallback, &mQuads.back());
    drawList->AddCallback(ImDrawCallback_ResetRenderState, nullptr);
}

void Presenter::quadCallback(const ImDrawList*, const ImDrawCmd* cmd) {
    const auto* q = static_cast<const QuadDraw*>(cmd->UserCallbackData);
    Presenter& p = *q->self;
    ImVec2 origin = ImGui::GetMainViewport()->Pos;
    float w = float(p.mExtent.width), h = float(p.mExtent.height);
    // The clip rectangle of the window the texture sits in, clamped to the framebuffer.
    float x0 = std::clamp(cmd->ClipRect.x - origin.x, 0.0f, w);
    float y0 = std::clamp(cmd->ClipRect.y - origin.y, 0.0f, h);
    float x1 = std::clamp(cmd->ClipRect.z - origin.x, 0.0f, w);
    float y1 = std::clamp(cmd->ClipRect.w - origin.y, 0.0f, h);
    if (x1 <= x0 || y1 <= y0) return;
    VkRect2D scissor{{int32_t(x0), int32_t(y0)}, {uint32_t(x1 - x0), uint32_t(y1 - y0)}};
    VkViewport viewport{0.0f, 0.0f, w, h, 0.0f, 1.0f};
    vkCmdBindPipeline(p.mCmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.mQuadPipeline);
    vkCmdSetViewport(p.mCmd, 0, 1, &viewport);
    vkCmdSetScissor(p.mCmd, 0, 1, &scissor);
    vkCmdBindDescriptorSets(p.mCmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.mQuadLayout, 0, 1, &q->set,
                            0, nullptr);
    float push[10] = {q->rect[0], q->rect[1], q->rect[2], q->rect[3], q->uv[0],
                      q->uv[1],   q->uv[2],   q->uv[3],   w,          h};
    vkCmdPushConstants(p.mCmd, p.mQuadLayout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(push), push);
    vkCmdDraw(p.mCmd, 4, 1, 0, 0);
}

void Presenter::render(ImageData* capture) {
    ImGui::Render();
    ImDrawData* draw = ImGui::GetDrawData();
    if (mSwapchainDirty) {
        vkDeviceWaitIdle(mDevice);
        destroySwapchain();
        createSwapchain();
    }
    if (mExtent.width == 0 || mExtent.height == 0) return;  // minimised

    uint32_t index = 0;
    VkResult r =
        vkAcquireNextImageKHR(mDevice, mSwapchain, UINT64_MAX, mAcquired, VK_NULL_HANDLE, &index);
    if (r == VK_ERROR_OUT_OF_DATE_KHR) {
        mSwapchainDirty = true;
        return;
    }
    if (r != VK_SUBOPTIMAL_KHR) check(r, "vkAcquireNextImageKHR");

    check(vkResetCommandBuffer(mCmd, 0), "vkResetCommandBuffer");
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(vkBeginCommandBuffer(mCmd, &bi), "vkBeginCommandBuffer");
    VkClearValue clear{};
    clear.color = {{0.08f, 0.08f, 0.09f, 1.0f}};
    VkRenderPassBeginInfo rbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rbi.renderPass = mRenderPass;
    rbi.framebuffer = mFramebuffers[index];
    rbi.renderArea.extent = mExtent;
    rbi.clearValueCount = 1;
    rbi.pClearValues = &clear;
    vkCmdBeginRenderPass(mCmd, &rbi, VK_SUBPASS_CONTENTS_INLINE);
    ImGui_ImplVulkan_RenderDrawData(draw, mCmd);
    vkCmdEndRenderPass(mCmd);

    std::shared_ptr<gpu::Buffer> readback;
    if (capture) {
        readback = mGpu->createBuffer(VkDeviceSize(mExtent.width) * mExtent.height * 4,
                                      "inspector.screenshot", true);
        VkImageMemoryBarrier ib{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        ib.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        ib.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        ib.oldLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
        ib.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        ib.srcQueueFamilyIndex = ib.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        ib.image = mImages[index];
        ib.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        vkCmdPipelineBarrier(mCmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                             VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &ib);
        VkBufferImageCopy region{};
        region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        region.imageExtent = {mExtent.width, mExtent.height, 1};
        vkCmdCopyImageToBuffer(mCmd, mImages[index], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                               readback->handle(), 1, &region);
        std::swap(ib.oldLayout, ib.newLayout);
        ib.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        ib.dstAccessMask = 0;
        vkCmdPipelineBarrier(mCmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0, nullptr, 0, nullptr, 1,
                             &ib);
    }
    check(vkEndCommandBuffer(mCmd), "vkEndCommandBuffer");

    VkPipelineStageFlags waitStage = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.waitSemaphoreCount = 1;
    si.pWaitSemaphores = &mAcquired;
    si.pWaitDstStageMask = &waitStage;
    si.commandBufferCount = 1;
    si.pCommandBuffers = &mCmd;
    si.signalSemaphoreCount = 1;
    si.pSignalSemaphores = &mRenderDone[index];
    check(vkResetFences(mDevice, 1, &mFence), "vkResetFences");
    check(vkQueueSubmit(mGpu->queue(), 1, &si, mFence), "vkQueueSubmit");
    // One frame in flight: the graph's next frame and texture uploads reuse the queue anyway.
    check(vkWaitForFences(mDevice, 1, &mFence, VK_TRUE, UINT64_MAX), "vkWaitForFences");

    VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
    pi.waitSemaphoreCount = 1;
    pi.pWaitSemaphores = &mRenderDone[index];
    pi.swapchainCount = 1;
    pi.pSwapchains = &mSwapchain;
    pi.pImageIndices = &index;
    r = vkQueuePresentKHR(mGpu->queue(), &pi);
    if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR)
        mSwapchainDirty = true;
    else
        check(r, "vkQueuePresentKHR");

    if (capture) {
        *capture = ImageData::make(mExtent.width, mExtent.height, 4);
        const auto* px = static_cast<const uint8_t*>(readback->mapped());
        const bool bgr =
            mFormat.format == VK_FORMAT_B8G8R8A8_UNORM || mFormat.format == VK_FORMAT_B8G8R8A8_SRGB;
        for (size_t i = 0; i < size_t(mExtent.width) * mExtent.height; ++i) {
            capture->pixels[i * 4 + 0] = px[i * 4 + (bgr ? 2 : 0)] / 255.0f;
            capture->pixels[i * 4 + 1] = px[i * 4 + 1] / 255.0f;
            capture->pixels[i * 4 + 2] = px[i * 4 + (bgr ? 0 : 2)] / 255.0f;
            capture->pixels[i * 4 + 3] = 1.0f;
        }
    }
}

}  // namespace loom::inspector
