#pragma once
// CPU-side scene description shared by every loader (Loom JSON, Mitsuba XML, glTF, OBJ) and
// by the GPU upload (SceneGpu). Units: world space, right-handed, y up by convention (Mitsuba
// scenes keep their own axes). Angles in degrees only where the source format uses them.
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace loom::scene {

struct Mesh {
    std::string name;
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;  // per vertex, or empty (flat shading)
    std::vector<glm::vec2> uvs;      // per vertex, or empty; (0,0) = top-left texel (row 0), as
                                     // Mitsuba (after its OBJ v flip) and glTF use them
    std::vector<glm::uvec3> indices;
    bool faceNormals = false;        // ignore vertex normals (Mitsuba face_normals)
};

enum class TextureKind { Bitmap, Checkerboard, Constant };

struct Texture {
    std::string name;
    TextureKind kind = TextureKind::Bitmap;
    std::string path;                 // bitmap file (resolved, absolute)
    uint32_t width = 0, height = 0;   // bitmap texels, loaded by the loader
    std::vector<float> rgba;          // linear RGBA texels (bitmap), row 0 = top
    glm::vec3 color0{0.4f}, color1{0.2f};  // checkerboard colours
    glm::vec2 uvScale{1.0f};          // Mitsuba to_uv scale
    bool isNormalMap = false;         // raw (not sRGB-decoded) data
};

enum class BsdfType {
    Diffuse,
    Dielectric,        // smooth (delta) glass
    RoughDielectric,
    Conductor,         // smooth (delta) mirror with complex IOR
    RoughConductor,
    Plastic,           // smooth dielectric coat over diffuse
    RoughPlastic,
    Null               // invisible to rays (pass-through boundary)
};

enum class Microfacet { GGX, Beckmann };

struct Material {
    std::string name;
    std::string origin;  // where it was defined ("file:line", "file: key"), for messages
    BsdfType type = BsdfType::Diffuse;
    glm::vec3 reflectance{0.5f};       // diffuse reflectance (Diffuse/Plastic)
    int reflectanceTexture = -1;       // index into Scene::textures
    glm::vec3 specularReflectance{1.0f};
    // Textured specular reflectance (Mitsuba conductors, e.g. veach-ajar's checkered floor).
    // Like reflectanceTexture it replaces the constant, which then holds the texture's mean.
    int specularReflectanceTexture = -1;
    glm::vec3 specularTransmittance{1.0f};
    float alpha = 0.0f;                // microfacet roughness (GGX/Beckmann alpha)
    Microfacet distribution = Microfacet::GGX;
    float eta = 1.5f;                  // int_ior / ext_ior (dielectric, plastic)
    glm::vec3 conductorEta{0.0f};      // complex IOR (conductor)
    glm::vec3 conductorK{1.0f};
    bool twoSided = false;
    int normalMap = -1;                // index into Scene::textures (tangent-space normal map)
    // SMS normalmap (Zeltner et al. 2020): interpolate slopes (-nx/nz, -ny/nz) between texels
    // instead of normals. Texels hold (n + 1) / 2 either way; tiles live in the texture's uvScale.
    bool normalMapUseSlopes = true;
    bool nonlinear = false;            // roughplastic 'nonlinear' flag
};

// Per-shape flags (bit mask) used by ray masks and by SMS/MNEE to tag special geometry.
enum ShapeFlags : uint32_t {
    kVisibleCamera = 1u << 0,
    kVisibleShadow = 1u << 1,
    kCausticCasterReflect = 1u << 2,
    kCausticCasterRefract = 1u << 3,
    kCausticReceiver = 1u << 4,
    kCausticEmitter = 1u << 5,   // SMS caustic_emitter_* tags
    kCausticBouncer = 1u << 6,   // SMS caustic_bouncer: inner specular vertex of multi-bounce chains
    kCausticMulti = 1u << 7,     // the caster/emitter tag was *_multi (multi-scatter SMS), not *_single
    kDefaultShapeFlags = kVisibleCamera | kVisibleShadow,
};

// One keyframe of a shape's per-frame rigid motion: the motion at `time` is
// translate * rotate * scale, applied after the shape's toWorld (scene/README.md).
struct ShapeKeyframe {
    float time = 0.0f;  // frame index (fractional allowed)
    glm::vec3 translate{0.0f};
    glm::quat rotate{1.0f, 0.0f, 0.0f, 0.0f};
    glm::vec3 scale{1.0f};
};

struct Shape {
    std::string name;
    std::string origin;  // where it was defined, for messages
    int mesh = -1;                 // index into Scene::meshes
    int material = -1;             // index into Scene::materials
    glm::mat4 toWorld{1.0f};
    glm::vec3 emission{0.0f};      // area light radiance (0 = not a light)
    uint32_t flags = kDefaultShapeFlags;
    uint32_t rayMask = 0xffu;      // user mask bits
    // Optional rigid motion over the shutter: toWorld at shutter close (identity = none).
    bool moving = false;
    glm::mat4 toWorldEnd{1.0f};
    // Optional per-frame motion (keyframes sorted by time; empty = static): object to world at
    // frame time t is shapeToWorldAt(shape, t) (Camera.h). Not blurred over the shutter.
    std::vector<ShapeKeyframe> path;
    // Optional deformation (animated heightfields): the object-space mesh at frame time t, with
    // the topology (indices) of `mesh`. SceneGpu re-tessellates the shape and rebuilds the BVH
    // and the triangle adjacency every frame; empty = the mesh does not change.
    std::function<Mesh(float)> deformation;
};

enum class LightType { Point, Spot, Directional, Environment, Constant };

struct Light {
    LightType type = LightType::Point;
    glm::vec3 position{0.0f};
    glm::vec3 direction{0.0f, 0.0f, -1.0f};
    glm::vec3 intensity{1.0f};     // W/sr (point/spot), radiance (env/constant), irradiance (dir)
    float cutoffAngle = 20.0f;     // spot, degrees
    float beamWidth = 15.0f;       // spot falloff start, degrees
    int envTexture = -1;           // environment map (lat-long)
    float scale = 1.0f;
    glm::mat4 toWorld{1.0f};       // environment rotation
    uint32_t flags = 0;            // kCausticEmitter (| kCausticMulti) for SMS-tagged lights
    std::string origin;            // where it was defined, for messages
};

struct CameraKeyframe {
    float time = 0.0f;             // frame index (fractional allowed)
    glm::vec3 origin{0.0f}, target{0.0f, 0.0f, -1.0f}, up{0.0f, 1.0f, 0.0f};
    float fovY = 45.0f;
};

enum class CameraType { Pinhole, ThinLens };

struct Camera {
    CameraType type = CameraType::Pinhole;
    // Camera-to-world; the camera looks down +z in its local frame (Mitsuba convention),
    // +y is up, +x is left (Mitsuba) — SceneGpu builds rays from this matrix.
    glm::mat4 toWorld{1.0f};
    float fov = 45.0f;             // degrees, along fovAxis
    enum class FovAxis { X, Y, Smaller, Larger } fovAxis = FovAxis::X;
    float apertureRadius = 0.0f;   // thin lens
    float focusDistance = 1.0f;
    float shutterOpen = 0.0f, shutterClose = 0.0f;  // in frames; equal = no motion blur
    uint32_t filmWidth = 0, filmHeight = 0;         // from the file (0 = unknown)
    std::vector<CameraKeyframe> path;               // optional per-frame animation
};

struct Scene {
    std::string sourceFile;
    std::vector<Mesh> meshes;
    std::vector<Material> materials;
    std::vector<Texture> textures;
    std::vector<Shape> shapes;
    std::vector<Light> lights;
    Camera camera;
    std::vector<std::string> warnings;  // unsupported features met while loading
};

}  // namespace loom::scene
