#pragma once
// The light-caster pairs of sample-space-partitioned SMS (Hong et al. 2025 Sec. 4.2): an
// emitter object (an SMS-tagged emissive shape, or a tagged point, spot or directional light)
// and a caster object (a shape tagged caustic_caster). ManifoldPrior keys its per-block lists
// by pair, PartitionedSMS chooses a pair, then a light point on its emitter and a seed towards
// its caster. GLSL side: shaders/lib/manifold/pairs.glsl.
#include <memory>
#include <string>

#include "core/gpu/Context.h"

namespace loom {

class ExecuteContext;
namespace scene {
struct Scene;
}

class ManifoldPairs {
public:
    // Builds the GPU tables for the context's scene (cached per scene); throws a UserError
    // naming `pass` when the scene has no casters, receivers or emitters.
    void build(ExecuteContext& ctx, const std::string& pass);
    void bind(gpu::Bindings& b) const;
    uint32_t pairs() const { return mEmitters * mCasters; }
    // Whether a caster of `s` is a rough conductor or dielectric (its chains then scatter
    // about offset normals: MANIFOLD_ROUGH_CASTERS, lib/manifold/walk.glsl).
    static bool roughCasters(const scene::Scene& s);

private:
    const scene::Scene* mScene = nullptr;
    std::shared_ptr<gpu::Buffer> mEmitterLights, mEmitterObjects, mCasterObjects;
    uint32_t mEmitters = 0, mCasters = 0;
};

}  // namespace loom
