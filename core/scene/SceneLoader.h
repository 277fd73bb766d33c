#pragma once
// CPU scene loading. loadScene() dispatches on the file extension:
//   .json  Loom scene (scenes/README.md)       .xml  Mitsuba 0.5/0.6, 2 and 3 scene
//   .gltf/.glb  glTF 2.0                        .obj  Wavefront OBJ + MTL   .ply  single mesh
// Bad input throws loom::UserError naming the file, line (and element/attribute) and what was
// expected. Unsupported features are skipped or approximated with one warning each (logged and
// kept in Scene::warnings) saying what was done instead.
#include <map>
#include <string>

#include "core/scene/Scene.h"

namespace loom::scene {

struct SceneLoadOptions {
    // Values for Mitsuba $variables, overriding <default> (like `mitsuba -Dname=value`). Some
    // scenes need them, e.g. the SMS roughness sweep (sms-plane/plane_rough_*.xml: alpha).
    std::map<std::string, std::string> defines;
};

Scene loadScene(const std::string& path, const SceneLoadOptions& options = {});

Scene loadJsonScene(const std::string& path);
Scene loadMitsubaScene(const std::string& path,
                       const std::map<std::string, std::string>& defines = {});
Scene loadGltfScene(const std::string& path);
Scene loadObjScene(const std::string& path);

// Helpers shared by the loaders.
namespace detail {

// Logs a warning and records it in scene.warnings.
void addWarning(Scene& scene, const std::string& message);
// `file` relative to `baseDir` unless absolute; normalised.
std::string resolvePath(const std::string& baseDir, const std::string& file);
// Adds a bitmap texture (deduplicated by path, raw flag and uv scale) and returns its index.
// raw = values as stored (normal maps, data); otherwise 8-bit/LDR colour files are decoded from
// sRGB to linear. A missing or unreadable file gives a warning naming `context`, the path
// tried and `fallback` (what the caller does instead), and returns -1.
int addBitmapTexture(Scene& scene, const std::string& path, bool raw, glm::vec2 uvScale,
                     const std::string& context,
                     const std::string& fallback = "using a constant instead");
// Mean linear RGB of a texture (checkerboards: mean of the two colours).
glm::vec3 textureAverage(const Texture& texture);
// Complex IOR of a named conductor ("Au", "Ag", "Cu", "Al", "Cr", ...; "none" = perfect
// mirror). Returns false for unknown names.
bool conductorIor(const std::string& name, glm::vec3& eta, glm::vec3& k);
std::string conductorNames();
// Mitsuba's named dielectric IORs ("bk7", "water", "air", "diamond", ...).
bool namedIor(const std::string& name, float& ior);
// Places a camera in front of the scene's bounding box (used when a file has none).
void setDefaultCamera(Scene& scene);
// Validates meshes (indices, finite positions) and shape/material/texture indices.
// Then applies the same physical range rules to every format's materials, emitters, lights and
// camera: non-finite or negative values are errors naming where they were defined; reflectance
// above 1 and a scene that cannot emit light are warnings.
void validateScene(Scene& scene);

}  // namespace detail
}  // namespace loom::scene
