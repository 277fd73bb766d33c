#pragma once
// Importance sampling of a lat-long environment map: a piecewise-constant 2D distribution
// proportional to luminance x sin(theta) per texel (pbrt-v3 Distribution2D, Sec. 13.6.7 and
// 14.2.4), built here and sampled on the GPU by shaders/lib/envmap.glsl (binary search of the
// marginal and conditional CDFs; pdf in solid angle through the sin(theta) Jacobian).
//
// Mapping (Mitsuba 3 'envmap', local frame, y up): u in [0,1) -> phi = 2 pi u, v in [0,1) ->
// theta = pi v from +y, d = (sin phi sin theta, cos theta, -cos phi sin theta); image row 0 is
// v = 0 (the +y pole). World directions are toWorld (rotation part) times local ones. Radiance
// is looked up with nearest-texel filtering so that it is piecewise constant like the pdf.
#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <vector>

#include "core/scene/Scene.h"

namespace loom::gpu {
class Buffer;
class Bindings;
class Context;
}  // namespace loom::gpu

namespace loom::scene {

class EnvMapDistribution {
public:
    // rgba: width * height linear RGBA texels, row 0 at the top (theta = 0). Only the rotation
    // of toWorld is kept (orthonormalised).
    EnvMapDistribution(const float* rgba, uint32_t width, uint32_t height,
                       const glm::mat4& toWorld = glm::mat4(1.0f));
    explicit EnvMapDistribution(const Texture& texture, const glm::mat4& toWorld = glm::mat4(1.0f));

    uint32_t width() const { return mWidth; }
    uint32_t height() const { return mHeight; }
    const glm::mat3& toWorld() const { return mToWorld; }

    // Distribution block (floats) read by envmap.glsl, W = width, H = height:
    //   [0, H)                      marginal density over v of each row
    //   [H, 2H + 1)                 marginal CDF (0 ... 1)
    //   [2H + 1, 2H + 1 + HW)       conditional densities over u, row-major
    //   [2H + 1 + HW, +H(W + 1))    conditional CDFs, W + 1 entries per row
    const std::vector<float>& distribution() const { return mDistribution; }
    // Linear RGB radiance, row-major (3 floats per texel).
    const std::vector<float>& radiance() const { return mRadiance; }

    // Mean luminance over the sphere, (1 / 4 pi) * integral of Y dw (texel solid angles exact).
    double averageLuminance() const { return mAverageLuminance; }

    // Densities of the sampling routine w.r.t. du dv, and in solid angle at a local direction
    // (pdf_uv / (2 pi^2 sin theta)). CPU references for tests.
    double pdfUv(glm::dvec2 uv) const;
    double pdfDirection(glm::dvec3 local) const;

    static glm::dvec3 direction(glm::dvec2 uv);
    static glm::dvec2 uv(glm::dvec3 local);

private:
    uint32_t mWidth = 0, mHeight = 0;
    glm::mat3 mToWorld{1.0f};
    double mAverageLuminance = 0.0;
    std::vector<double> mJoint;  // normalised texel densities over (u, v), row-major
    std::vector<float> mDistribution;
    std::vector<float> mRadiance;
};

// All environment maps of a scene in one float buffer, bound as `SceneEnvMaps` (uint fields
// stored as float bits):
//   [0]               map count
//   [1 + k]           offset (in floats) of map k's record
//   record +0..+3     width, height, radiance offset, distribution offset (relative to record)
//   record +4..+15    toWorld as three vec3 columns, each padded to 4 floats
//   record +16..+27   toLocal (its transpose), same layout
//   record +32        radiance (3 W H), then the distribution block described above
std::vector<float> packEnvMapData(const std::vector<EnvMapDistribution>& maps);
std::shared_ptr<gpu::Buffer> packEnvMaps(gpu::Context& gpu,
                                         const std::vector<EnvMapDistribution>& maps);
// Binds the buffer from packEnvMaps under the name envmap.glsl declares.
void bindEnvMaps(gpu::Bindings& bindings, const std::shared_ptr<gpu::Buffer>& buffer);

}  // namespace loom::scene
