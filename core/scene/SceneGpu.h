#pragma once
// The scene on the GPU: world-space triangles (shapes flattened, contiguous per shape), the
// BVH, materials, textures, the light list with its selection CDF, and per-frame camera poses.
// GLSL side: shaders/lib/scene.glsl, lights.glsl, bvh.glsl, material.glsl.
#include <memory>
#include <string>

#include "core/gpu/Context.h"
#include "core/scene/Scene.h"

namespace loom::scene {

struct SceneStats {
    size_t triangles = 0, shapes = 0, materials = 0, textures = 0, lights = 0,
           emissiveTriangles = 0;
    size_t bvhNodes = 0;
    double buildMs = 0.0;
    // The last per-frame update of moving and deforming shapes: all of it (re-tessellation,
    // uploads, BVH), the BVH build, and the triangle adjacency within it.
    double updateMs = 0.0, bvhBuildMs = 0.0, adjacencyMs = 0.0;
};

class SceneGpu {
public:
    SceneGpu(gpu::Context& gpu, Scene scene);
    ~SceneGpu();

    // Binds every scene buffer by the GLSL names of the scene libraries.
    void bind(gpu::Bindings& bindings) const;
    // Camera poses and moving shapes (Shape::path) for frame time t (in frames) at the given
    // aspect ratio; uploads when changed. Call once per frame: the previous frame (motion
    // vectors, and the previous geometry that scene_select_frame switches to) is the last
    // call's, so calling again with the same time means no motion.
    void setFrame(float time, uint32_t width, uint32_t height);
    // Replaces the camera (Lua / inspector); bumps revision().
    void setCamera(const Camera& camera);

    const Scene& cpu() const { return mScene; }
    // Whether shapes move over the camera's shutter (moving shapes and an open shutter): then
    // kernels need the motion-blur code of the BVH and the surface points, compiled in only
    // with LOOM_SHAPE_MOTION_BLUR (Renderer sets it), since it slows static traversal.
    bool shapesMoveOverShutter() const;
    // The material types the shapes use (bit t: BsdfType t) and the light types of the light
    // list (bit t: LIGHT t in scene.glsl): kernels are compiled for these only
    // (LOOM_SCENE_MATERIALS and LOOM_SCENE_LIGHTS, set by the Renderer), since llvmpipe runs
    // the code of every if-block, taken or not.
    uint32_t materialTypes() const { return mMaterialTypes; }
    uint32_t lightTypes() const { return mLightTypes; }
    // The texture slots the shapes' materials use (bit 0 reflectance, 1 specular reflectance,
    // 2 normal map): LOOM_SCENE_TEXTURES.
    uint32_t textureUses() const { return mTextureUses; }
    // Whether a camera pose of the last setFrame (shutter open or close, this frame or the
    // previous) is a thin lens with an aperture: LOOM_SCENE_THIN_LENS.
    bool thinLens() const;
    const SceneStats& stats() const { return mStats; }
    // Changes whenever the camera or frame time changes: passes with history reset on it.
    uint64_t revision() const { return mRevision; }
    // World-space bounding sphere.
    glm::vec4 boundingSphere() const { return mBounds; }

private:
    // Moves shapes with a keyframe path to frame time `frameTime` at shutter open (vertices,
    // BVH, the per-shape previous-frame maps of scene.glsl's previous_position) and, when the
    // shutter is open for a while, to shutter close (motion blur); a no-op for static scenes.
    void updateShapes(float frameTime, bool firstFrame);
    // The previous frame becomes this one: identity motion maps, no previous geometry.
    void settleShapes();
    // Per moving shape, the map from this frame's positions to the previous frame's.
    void uploadMotionRows();

    struct Impl;
    std::unique_ptr<Impl> mImpl;
    gpu::Context& mGpu;
    Scene mScene;
    SceneStats mStats;
    glm::vec4 mBounds{0.0f};
    uint64_t mRevision = 1;
    float mTime = -1.0f;
    float mShutterOpen = 0.0f, mShutterClose = 0.0f;  // of the last updateShapes
    uint32_t mWidth = 0, mHeight = 0;
    bool mCameraDirty = true;
    bool mPreviousDiffers = false;  // the previous frame's camera or shapes differ from this one's
    uint32_t mMaterialTypes = 0, mLightTypes = 0, mTextureUses = 0;  // kernel specialisation
};

}  // namespace loom::scene
