// ImageLoader: an image file (EXR, PFM, HDR, PNG, JPEG, ...; core/image/ImageFile.cpp) as a texture
// at its own size.
#include <filesystem>

#include "core/graph/RenderGraph.h"
#include "core/image/Image.h"

namespace loom {

class ImageLoaderPass : public Pass {
public:
    void reflect(PassReflection& r) const override {
        auto out = r.outputTexture("output", gpu::Format::RGBA32F)
                       .doc("the image (rgba32f, the file's own size)");
        if (mWidth > 0) out.fixedSize(mWidth, mHeight);
        r.param("path", "").doc("image file, relative to the graph file");
        r.param("linearize", true).doc("decode 8-bit sRGB files (PNG/JPG) to linear values");
    }
    void onParamChanged(const std::string& name) override {
        if (name == "linearize") mImage.reset();
        if (name != "path") return;
        // Read only the header now so the graph knows the size; pixels load on first use. A
        // file that cannot be read leaves the previous image and size in place (Pass::setParam
        // restores the previous path).
        uint32_t width = 0, height = 0;
        std::string path = resolvePath(param<std::string>("path"));
        if (!path.empty()) {
            try {
                readImageSize(path, width, height);
            } catch (const UserError& e) {
                throw ParamError(std::string("parameter 'path': ") + e.what());
            }
        }
        mImage.reset();
        mWidth = width;
        mHeight = height;
    }
    bool paramChangesPorts(const std::string& name) const override { return name == "path"; }
    void execute(ExecuteContext& ctx) override {
        // Upload once into a private image; copy each frame because the output texture may
        // share memory with other transients between frames.
        if (!mImage) {
            std::string path = resolvePath(param<std::string>("path"));
            if (path.empty()) throw UserError("parameter 'path' is empty");
            ImageData data = readImage(path, param<bool>("linearize"));
            mImage = ctx.gpu().createImage(data.width, data.height, gpu::Format::RGBA32F, path);
            uploadImage(ctx.gpu(), *mImage, data);
        }
        ctx.cmd().copyImage(*mImage, *ctx.texture("output"));
    }

private:
    uint32_t mWidth = 0, mHeight = 0;
    std::shared_ptr<gpu::Image> mImage;
};

LOOM_REGISTER_PASS(ImageLoaderPass, "ImageLoader", "Loads an image file as a texture");

}  // namespace loom
