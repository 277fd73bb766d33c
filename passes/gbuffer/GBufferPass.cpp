// GBuffer: V-buffer of the primary hits plus depth, normals, albedo, roughness, motion vectors
// and the film/lens sample of each pixel. See README.md.
#include "core/graph/KernelParams.h"
#include "core/graph/RenderGraph.h"
#include "core/scene/SceneGpu.h"

namespace loom {

namespace {
struct Output {
    const char* port;
    const char* glsl;
    gpu::Format format;
    const char* doc;
};
const Output kOutputs[] = {
    {"vbuffer", "vbufferImage", gpu::Format::RGBA32UI,
     "x: triangle id (~0 = miss), yz: barycentrics (float bits), w: shape id"},
    {"depth", "depthImage", gpu::Format::R32F, "view-space depth along the camera axis (0 = miss)"},
    {"normal", "normalImage", gpu::Format::RGBA32F, "shading normal (after normal mapping)"},
    {"geoNormal", "geoNormalImage", gpu::Format::RGBA32F, "geometric normal"},
    {"position", "positionImage", gpu::Format::RGBA32F, "world position, w = 1 on hits"},
    {"albedo", "albedoImage", gpu::Format::RGBA32F, "diffuse reflectance (textured)"},
    {"roughness", "roughnessImage", gpu::Format::R32F, "microfacet alpha (0 = smooth)"},
    {"motion", "motionImage", gpu::Format::RG32F,
     "previous-frame film position minus current, pixels (camera and shape motion)"},
    {"sample", "sampleImage", gpu::Format::RGBA32F, "subpixel offset xy, lens sample zw"},
};
}  // namespace

class GBufferPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        for (const auto& o : kOutputs) r.outputTexture(o.port, o.format).doc(o.doc);
        r.param("jitter", true).doc("random subpixel position per frame (else pixel centres)");
        r.param("motionBlur", false).doc("sample time over the shutter (camera and moving shapes)");
    }
    void compile(ShaderLibrary& shaders) override {
        mPipeline = compileKernel(*this, shaders, "passes/gbuffer/gbuffer.comp");
    }
    void execute(ExecuteContext& ctx) override {
        gpu::Bindings b;
        ctx.scene().bind(b);
        for (const auto& o : kOutputs) b.set(o.glsl, ctx.texture(o.port));
        KernelParams(*this, *mPipeline, ctx).dispatch(ctx, b, ctx.width(), ctx.height());
    }

private:
    std::shared_ptr<gpu::ComputePipeline> mPipeline;
};

LOOM_REGISTER_PASS(GBufferPass, "GBuffer",
                   "Primary-hit V-buffer, depth, normals, albedo, roughness, motion vectors");

}  // namespace loom
