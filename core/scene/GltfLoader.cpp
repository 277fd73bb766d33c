// glTF 2.0 (.gltf/.glb) through tinygltf: triangle primitives, metallic-roughness materials
// mapped to the closest Loom BSDF, normal maps, KHR_materials_transmission/ior/
// emissive_strength, cameras and KHR_lights_punctual.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

#include <fmt/format.h>
#include <tiny_gltf.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "core/scene/SceneLoader.h"
#include "core/scene/Shapes.h"
#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom::scene {

namespace {

namespace fs = std::filesystem;
using detail::addWarning;

float srgbToLinear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

class GltfLoader {
public:
    GltfLoader(Scene& scene, const std::string& path) : mScene(scene), mPath(path) {}

    void load() {
        tinygltf::TinyGLTF loader;
        std::string err, warn;
        bool binary =
            fs::path(mPath).extension() == ".glb" || fs::path(mPath).extension() == ".GLB";
        bool ok = binary ? loader.LoadBinaryFromFile(&mModel, &err, &warn, mPath)
                         : loader.LoadASCIIFromFile(&mModel, &err, &warn, mPath);
        auto trim = [](std::string s) {
            while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
            return s;
        };
        if (!ok) throw UserError(mPath + ": cannot load glTF: " + trim(err.empty() ? warn : err));
        if (!trim(warn).empty()) addWarning(mScene, mPath + ": " + trim(warn));
        for (const std::string& ext : mModel.extensionsRequired) {
            static const char* kKnown[] = {"KHR_lights_punctual", "KHR_materials_transmission",
                                           "KHR_materials_ior", "KHR_materials_emissive_strength"};
            if (std::find(std::begin(kKnown), std::end(kKnown), ext) == std::end(kKnown))
                addWarning(mScene, fmt::format("{}: required extension {} is not supported; the "
                                               "scene may render incorrectly",
                                               mPath, ext));
        }
        if (mModel.scenes.empty()) throw UserError(mPath + ": glTF file has no scenes");
        int sceneIndex = mModel.defaultScene >= 0 ? mModel.defaultScene : 0;
        if (sceneIndex >= int(mModel.scenes.size()))
            throw UserError(fmt::format("{}: default scene {} does not exist", mPath, sceneIndex));
        for (int n : mModel.scenes[size_t(sceneIndex)].nodes) visit(n, glm::mat4(1.0f), 0);
        if (mScene.shapes.empty()) throw UserError(mPath + ": glTF scene has no triangle meshes");
        if (!mHaveCamera) detail::setDefaultCamera(mScene);
        bool emissive = std::any_of(mScene.shapes.begin(), mScene.shapes.end(),
                                    [](const Shape& s) { return glm::length(s.emission) > 0.0f; });
        if (mScene.lights.empty() && !emissive) {
            Light env;
            env.type = LightType::Constant;
            mScene.lights.push_back(env);
            addWarning(mScene, mPath +
                                   ": no lights or emissive materials; added a constant "
                                   "environment light of radiance 1");
        }
    }

private:
    Scene& mScene;
    std::string mPath;
    tinygltf::Model mModel;
    std::map<std::pair<int, int>, int> mMeshCache;      // (mesh, primitive) -> Scene mesh
    std::map<int, int> mMaterialCache;                  // glTF material -> Scene material
    std::map<int, glm::vec3> mEmission;                 // glTF material -> emitted radiance
    std::map<std::pair<int, bool>, int> mTextureCache;  // (glTF texture, raw) -> Scene texture
    int mDefaultMaterial = -1;
    bool mHaveCamera = false;

    [[noreturn]] void fail(const std::string& what) const { throw UserError(mPath + ": " + what); }

    static glm::mat4 nodeMatrix(const tinygltf::Node& node) {
        if (node.matrix.size() == 16) {
            glm::mat4 m;
            for (int i = 0; i < 16; ++i)
                glm::value_ptr(m)[i] = float(node.matrix[size_t(i)]);  // column-major
            return m;
        }
        glm::mat4 t(1.0f), r(1.0f), s(1.0f);
        if (node.translation.size() == 3)
            t = glm::translate(glm::mat4(1.0f), glm::vec3(node.translation[0], node.translation[1],
                                                          node.translation[2]));
        if (node.rotation.size() == 4)
            r = glm::mat4_cast(glm::quat(float(node.rotation[3]), float(node.rotation[0]),
                                         float(node.rotation[1]), float(node.rotation[2])));
        if (node.scale.size() == 3)
            s = glm::scale(glm::mat4(1.0f), glm::vec3(node.scale[0], node.scale[1], node.scale[2]));
        return t * r * s;
    }

    void visit(int index, const glm::mat4& parent, int depth) {
        if (index < 0 || index >= int(mModel.nodes.size()))
            fail(fmt::format("node {} does not exist", index));
        if (depth > 256) fail("node hierarchy is too deep (cycle?)");
        const tinygltf::Node& node = mModel.nodes[size_t(index)];
        glm::mat4 world = parent * nodeMatrix(node);
        if (node.mesh >= 0) addMesh(node, world);
        if (node.camera >= 0) addCamera(node, world);
        if (auto it = node.extensions.find("KHR_lights_punctual"); it != node.extensions.end())
            if (it->second.Has("light")) addLight(it->second.Get("light").GetNumberAsInt(), world);
        if (node.skin >= 0 || !node.weights.empty())
            addWarning(mScene,
                       fmt::format("{}: node '{}': skinning/morph targets are not supported; "
                                   "the bind pose is used",
                                   mPath, node.name));
        for (int c : node.children) visit(c, world, depth + 1);
    }

    // Reads `accessor` as floats (normalised integers are mapped to [0,1] / [-1,1]).
    std::vector<float> readFloats(int accessorIndex, int expectComponents,
                                  const std::string& what) {
        if (accessorIndex < 0 || accessorIndex >= int(mModel.accessors.size()))
            fail(fmt::format("{}: accessor {} does not exist", what, accessorIndex));
        const tinygltf::Accessor& acc = mModel.accessors[size_t(accessorIndex)];
        int comps = tinygltf::GetNumComponentsInType(uint32_t(acc.type));
        if (comps != expectComponents)
            fail(fmt::format("{}: accessor {} has {} components, expected {}", what, accessorIndex,
                             comps, expectComponents));
        if (acc.sparse.isSparse)
            addWarning(mScene, fmt::format("{}: {}: sparse accessors are not supported; the base "
                                           "values are used",
                                           mPath, what));
        std::vector<float> out(acc.count * size_t(comps), 0.0f);
        if (acc.bufferView < 0) return out;  // all zeros by the spec
        const uint8_t* base = nullptr;
        size_t stride = 0;
        access(acc, comps, what, base, stride);
        for (size_t i = 0; i < acc.count; ++i)
            for (int c = 0; c < comps; ++c) {
                const uint8_t* p =
                    base + i * stride +
                    size_t(c) *
                        size_t(tinygltf::GetComponentSizeInBytes(uint32_t(acc.componentType)));
                float v = 0.0f;
                switch (acc.componentType) {
                    case TINYGLTF_COMPONENT_TYPE_FLOAT:
                        std::memcpy(&v, p, 4);
                        break;
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                        v = acc.normalized ? *p / 255.0f : float(*p);
                        break;
                    case TINYGLTF_COMPONENT_TYPE_BYTE: {
                        auto s = int8_t(*p);
                        v = acc.normalized ? std::max(s / 127.0f, -1.0f) : float(s);
                        break;
                    }
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                        uint16_t s;
                        std::memcpy(&s, p, 2);
                        v = acc.normalized ? s / 65535.0f : float(s);
                        break;
                    }
                    case TINYGLTF_COMPONENT_TYPE_SHORT: {
                        int16_t s;
                        std::memcpy(&s, p, 2);
                        v = acc.normalized ? std::max(s / 32767.0f, -1.0f) : float(s);
                        break;
                    }
                    default:
                        fail(fmt::format("{}: unsupported component type {}", what,
                                         acc.componentType));
                }
                out[i * size_t(comps) + size_t(c)] = v;
            }
        return out;
    }

    std::vector<uint32_t> readIndices(int accessorIndex, const std::string& what) {
        if (accessorIndex < 0 || accessorIndex >= int(mModel.accessors.size()))
            fail(fmt::format("{}: accessor {} does not exist", what, accessorIndex));
        const tinygltf::Accessor& acc = mModel.accessors[size_t(accessorIndex)];
        if (acc.type != TINYGLTF_TYPE_SCALAR) fail(what + ": index accessor is not scalar");
        const uint8_t* base = nullptr;
        size_t stride = 0;
        access(acc, 1, what, base, stride);
        std::vector<uint32_t> out(acc.count);
        for (size_t i = 0; i < acc.count; ++i) {
            const uint8_t* p = base + i * stride;
            switch (acc.componentType) {
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                    out[i] = *p;
                    break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                    uint16_t v;
                    std::memcpy(&v, p, 2);
                    out[i] = v;
                    break;
                }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
                    std::memcpy(&out[i], p, 4);
                    break;
                default:
                    fail(what + ": indices must be unsigned byte/short/int");
            }
        }
        return out;
    }

    // Pointer to the first element and the element stride, with bounds checks.
    void access(const tinygltf::Accessor& acc, int comps, const std::string& what,
                const uint8_t*& base, size_t& stride) {
        if (acc.bufferView < 0 || acc.bufferView >= int(mModel.bufferViews.size()))
            fail(fmt::format("{}: buffer view {} does not exist", what, acc.bufferView));
        const tinygltf::BufferView& view = mModel.bufferViews[size_t(acc.bufferView)];
        if (view.buffer < 0 || view.buffer >= int(mModel.buffers.size()))
            fail(fmt::format("{}: buffer {} does not exist", what, view.buffer));
        const tinygltf::Buffer& buffer = mModel.buffers[size_t(view.buffer)];
        int compSize = tinygltf::GetComponentSizeInBytes(uint32_t(acc.componentType));
        if (compSize <= 0)
            fail(fmt::format("{}: unknown component type {}", what, acc.componentType));
        size_t elem = size_t(compSize) * size_t(comps);
        stride = view.byteStride ? view.byteStride : elem;
        size_t begin = view.byteOffset + acc.byteOffset;
        size_t end = acc.count ? begin + (acc.count - 1) * stride + elem : begin;
        if (end > view.byteOffset + view.byteLength || end > buffer.data.size())
            fail(fmt::format("{}: accessor reads past the end of its buffer", what));
        base = buffer.data.data() + begin;
    }

    int texture(int textureIndex, bool raw, const std::string& what) {
        auto key = std::make_pair(textureIndex, raw);
        if (auto it = mTextureCache.find(key); it != mTextureCache.end()) return it->second;
        int result = -1;
        if (textureIndex < 0 || textureIndex >= int(mModel.textures.size())) {
            addWarning(mScene, fmt::format("{}: {}: texture {} does not exist; ignored", mPath,
                                           what, textureIndex));
        } else if (int source = mModel.textures[size_t(textureIndex)].source;
                   source < 0 || source >= int(mModel.images.size()) ||
                   mModel.images[size_t(source)].image.empty()) {
            addWarning(mScene, fmt::format("{}: {}: texture {} has no decodable image; ignored",
                                           mPath, what, textureIndex));
        } else {
            const tinygltf::Image& img = mModel.images[size_t(source)];
            Texture t;
            t.name = img.uri.empty() ? img.name : img.uri;
            t.kind = TextureKind::Bitmap;
            t.path = img.uri.empty()
                         ? ""
                         : detail::resolvePath(fs::path(mPath).parent_path().string(), img.uri);
            t.width = uint32_t(img.width);
            t.height = uint32_t(img.height);
            t.isNormalMap = raw;
            size_t n = size_t(img.width) * size_t(img.height);
            int comps = img.component;
            bool sixteen = img.bits == 16;
            t.rgba.resize(n * 4);
            for (size_t p = 0; p < n; ++p) {
                float c[4] = {0, 0, 0, 1};
                for (int k = 0; k < comps && k < 4; ++k) {
                    size_t i = p * size_t(comps) + size_t(k);
                    c[k] = sixteen
                               ? float(img.image[i * 2] | (img.image[i * 2 + 1] << 8)) / 65535.0f
                               : float(img.image[i]) / 255.0f;
                }
                if (comps < 3) c[1] = c[2] = c[0];
                // glTF colour textures are sRGB encoded; normal maps and data are linear.
                if (!raw)
                    for (int k = 0; k < 3; ++k) c[k] = srgbToLinear(c[k]);
                std::copy(c, c + 4, t.rgba.data() + p * 4);
            }
            mScene.textures.push_back(std::move(t));
            result = int(mScene.textures.size() - 1);
        }
        mTextureCache[key] = result;
        return result;
    }

    static double extNumber(const tinygltf::ExtensionMap& ext, const char* name, const char* key,
                            double def, bool& present) {
        auto it = ext.find(name);
        present = it != ext.end();
        if (!present || !it->second.Has(key)) return def;
        return it->second.Get(key).GetNumberAsDouble();
    }

    // glTF metallic-roughness -> the closest Loom BSDF:
    //  - alpha = roughnessFactor^2 (glTF roughness is perceptual; GGX alpha is its square);
    //    below 1e-3 the smooth (delta) variant is used.
    //  - transmissionFactor >= 0.5 (KHR_materials_transmission): (rough) dielectric with
    //    eta = KHR_materials_ior (default 1.5), transmittance = baseColor.
    //  - metallicFactor >= 0.5: (rough) conductor with eta = 0, k = 1 (Fresnel 1, a white mirror)
    //    tinted by baseColor, i.e. Schlick F0 = baseColor without the grazing whitening.
    //  - otherwise the dielectric base: (rough) plastic, diffuse baseColor under a GGX coat of
    //    eta = ior. Intermediate metallic/transmission values snap to the nearer end (warning).
    //  - metallicRoughnessTexture is not sampled (the factors are used; warning).
    int material(int index) {
        if (index < 0) {
            if (mDefaultMaterial < 0) {
                mScene.materials.push_back(Material{});
                mScene.materials.back().name = "default";
                mDefaultMaterial = int(mScene.materials.size() - 1);
            }
            return mDefaultMaterial;
        }
        if (auto it = mMaterialCache.find(index); it != mMaterialCache.end()) return it->second;
        if (index >= int(mModel.materials.size()))
            fail(fmt::format("material {} does not exist", index));
        const tinygltf::Material& g = mModel.materials[size_t(index)];
        std::string what =
            fmt::format("material '{}'", g.name.empty() ? std::to_string(index) : g.name);
        const auto& pbr = g.pbrMetallicRoughness;
        glm::vec3 base(pbr.baseColorFactor[0], pbr.baseColorFactor[1], pbr.baseColorFactor[2]);
        float metallic = float(pbr.metallicFactor), rough = float(pbr.roughnessFactor);
        bool hasTransmission = false, hasIor = false, hasStrength = false;
        float transmission = float(extNumber(g.extensions, "KHR_materials_transmission",
                                             "transmissionFactor", 0.0, hasTransmission));
        float ior = float(extNumber(g.extensions, "KHR_materials_ior", "ior", 1.5, hasIor));
        float strength = float(extNumber(g.extensions, "KHR_materials_emissive_strength",
                                         "emissiveStrength", 1.0, hasStrength));
        Material m;
        m.name = g.name.empty() ? fmt::format("material{}", index) : g.name;
        m.origin = fmt::format("{}: materials[{}]", mPath, index);
        m.alpha = rough * rough;
        m.distribution = Microfacet::GGX;
        m.eta = ior > 1.0f ? ior : 1.5f;
        m.twoSided = g.doubleSided;
        bool smooth = m.alpha < 1e-3f;
        int baseTex =
            pbr.baseColorTexture.index >= 0 ? texture(pbr.baseColorTexture.index, false, what) : -1;
        if (transmission >= 0.5f) {
            m.type = smooth ? BsdfType::Dielectric : BsdfType::RoughDielectric;
            m.specularTransmittance = base;
        } else if (metallic >= 0.5f) {
            m.type = smooth ? BsdfType::Conductor : BsdfType::RoughConductor;
            m.conductorEta = glm::vec3(0.0f);
            m.conductorK = glm::vec3(1.0f);
            m.specularReflectance = base;
            if (baseTex >= 0) {
                m.specularReflectanceTexture = baseTex;
                m.specularReflectance =
                    base * detail::textureAverage(mScene.textures[size_t(baseTex)]);
            }
        } else {
            m.type = smooth ? BsdfType::Plastic : BsdfType::RoughPlastic;
            m.reflectance = base;
            if (baseTex >= 0) {
                m.reflectanceTexture = baseTex;
                m.reflectance = base * detail::textureAverage(mScene.textures[size_t(baseTex)]);
            }
        }
        if (baseTex >= 0 && base != glm::vec3(1.0f))
            addWarning(mScene, fmt::format("{}: {}: baseColorFactor x baseColorTexture is not "
                                           "supported; the texture is used alone",
                                           mPath, what));
        if ((metallic > 0.0f && metallic < 1.0f && transmission < 0.5f) ||
            (transmission > 0.0f && transmission < 1.0f))
            addWarning(mScene, fmt::format("{}: {}: metallic {} / transmission {} snapped to the "
                                           "nearer of 0 and 1",
                                           mPath, what, metallic, transmission));
        if (pbr.metallicRoughnessTexture.index >= 0)
            addWarning(mScene, fmt::format("{}: {}: metallicRoughnessTexture is not supported; the "
                                           "factors are used",
                                           mPath, what));
        if (g.normalTexture.index >= 0) {
            m.normalMap = texture(g.normalTexture.index, true, what + " normalTexture");
            m.normalMapUseSlopes = false;
            if (g.normalTexture.scale != 1.0)
                addWarning(mScene, fmt::format("{}: {}: normalTexture.scale {} ignored", mPath,
                                               what, g.normalTexture.scale));
        }
        if (g.alphaMode != "OPAQUE" && !g.alphaMode.empty())
            addWarning(mScene, fmt::format("{}: {}: alphaMode {} is not supported; rendered opaque",
                                           mPath, what, g.alphaMode));
        glm::vec3 emission(0.0f);
        if (g.emissiveFactor.size() == 3)
            emission =
                glm::vec3(g.emissiveFactor[0], g.emissiveFactor[1], g.emissiveFactor[2]) * strength;
        if (g.emissiveTexture.index >= 0 && glm::length(emission) > 0.0f) {
            int tex = texture(g.emissiveTexture.index, false, what + " emissiveTexture");
            if (tex >= 0) {
                emission *= detail::textureAverage(mScene.textures[size_t(tex)]);
                addWarning(mScene, fmt::format("{}: {}: emissiveTexture approximated by its mean",
                                               mPath, what));
            }
        }
        mScene.materials.push_back(m);
        int result = int(mScene.materials.size() - 1);
        mMaterialCache[index] = result;
        mEmission[index] = emission;
        return result;
    }

    void addMesh(const tinygltf::Node& node, const glm::mat4& world) {
        if (node.mesh >= int(mModel.meshes.size()))
            fail(fmt::format("mesh {} does not exist", node.mesh));
        const tinygltf::Mesh& gm = mModel.meshes[size_t(node.mesh)];
        for (size_t pi = 0; pi < gm.primitives.size(); ++pi) {
            const tinygltf::Primitive& prim = gm.primitives[pi];
            std::string what = fmt::format("mesh '{}' primitive {}", gm.name, pi);
            if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES) {
                addWarning(mScene,
                           fmt::format("{}: {}: mode {} (not triangles) is not supported; skipped",
                                       mPath, what, prim.mode));
                continue;
            }
            auto key = std::make_pair(node.mesh, int(pi));
            auto it = mMeshCache.find(key);
            if (it == mMeshCache.end()) {
                auto pos = prim.attributes.find("POSITION");
                if (pos == prim.attributes.end()) fail(what + ": no POSITION attribute");
                Mesh mesh;
                mesh.name = gm.name.empty() ? fmt::format("mesh{}", node.mesh) : gm.name;
                std::vector<float> p = readFloats(pos->second, 3, what + " POSITION");
                for (size_t i = 0; i + 2 < p.size(); i += 3)
                    mesh.positions.push_back({p[i], p[i + 1], p[i + 2]});
                if (auto n = prim.attributes.find("NORMAL"); n != prim.attributes.end()) {
                    std::vector<float> v = readFloats(n->second, 3, what + " NORMAL");
                    for (size_t i = 0; i + 2 < v.size(); i += 3)
                        mesh.normals.push_back({v[i], v[i + 1], v[i + 2]});
                }
                if (auto t = prim.attributes.find("TEXCOORD_0"); t != prim.attributes.end()) {
                    std::vector<float> v = readFloats(t->second, 2, what + " TEXCOORD_0");
                    for (size_t i = 0; i + 1 < v.size(); i += 2)
                        mesh.uvs.push_back({v[i], v[i + 1]});
                }
                std::vector<uint32_t> idx;
                if (prim.indices >= 0) {
                    idx = readIndices(prim.indices, what + " indices");
                } else {
                    idx.resize(mesh.positions.size());
                    for (size_t i = 0; i < idx.size(); ++i) idx[i] = uint32_t(i);
                }
                for (size_t i = 0; i + 2 < idx.size(); i += 3)
                    mesh.indices.push_back({idx[i], idx[i + 1], idx[i + 2]});
                validateMesh(mesh, mPath + ": " + what);
                // glTF: flat shading when normals are absent.
                if (mesh.normals.empty()) mesh.faceNormals = true;
                mScene.meshes.push_back(std::move(mesh));
                it = mMeshCache.emplace(key, int(mScene.meshes.size() - 1)).first;
            }
            Shape s;
            s.name = node.name.empty() ? mScene.meshes[size_t(it->second)].name : node.name;
            s.mesh = it->second;
            s.material = material(prim.material);
            if (prim.material >= 0) s.emission = mEmission[prim.material];
            s.toWorld = world;
            s.origin = fmt::format("{}: node '{}'", mPath, node.name);
            mScene.shapes.push_back(s);
        }
    }

    void addCamera(const tinygltf::Node& node, const glm::mat4& world) {
        if (mHaveCamera) return;  // the first camera in traversal order
        if (node.camera >= int(mModel.cameras.size()))
            fail(fmt::format("camera {} does not exist", node.camera));
        const tinygltf::Camera& c = mModel.cameras[size_t(node.camera)];
        Camera& cam = mScene.camera;
        cam = Camera{};
        // glTF cameras look down -z with +x right; Loom (Mitsuba) looks down +z with +x left:
        // a 180 degree turn about y maps one onto the other.
        cam.toWorld = world * glm::scale(glm::mat4(1.0f), glm::vec3(-1.0f, 1.0f, -1.0f));
        cam.fovAxis = Camera::FovAxis::Y;
        if (c.type == "perspective") {
            cam.fov = glm::degrees(float(c.perspective.yfov));
        } else {
            cam.fov = 40.0f;
            addWarning(mScene, fmt::format("{}: camera '{}': {} cameras are not supported; using a "
                                           "perspective camera with a 40 degree vertical fov",
                                           mPath, c.name, c.type));
        }
        mHaveCamera = true;
    }

    void addLight(int index, const glm::mat4& world) {
        if (index < 0 || index >= int(mModel.lights.size()))
            fail(fmt::format("light {} does not exist", index));
        const tinygltf::Light& g = mModel.lights[size_t(index)];
        glm::vec3 color(1.0f);
        if (g.color.size() == 3) color = glm::vec3(g.color[0], g.color[1], g.color[2]);
        Light l;
        // KHR_lights_punctual intensities are photometric (cd, lux); they are used as W/sr and
        // W/m^2 as they are, which keeps relative light strengths.
        l.intensity = color * float(g.intensity);
        l.position = glm::vec3(world[3]);
        l.direction =
            glm::normalize(glm::vec3(world * glm::vec4(0, 0, -1, 0)));  // lights shine along -z
        l.toWorld = world;
        if (g.type == "point") {
            l.type = LightType::Point;
        } else if (g.type == "spot") {
            l.type = LightType::Spot;
            l.cutoffAngle = glm::degrees(float(g.spot.outerConeAngle));
            l.beamWidth = glm::degrees(float(g.spot.innerConeAngle));
        } else if (g.type == "directional") {
            l.type = LightType::Directional;
        } else {
            addWarning(mScene, fmt::format("{}: light '{}': type '{}' is not supported; skipped",
                                           mPath, g.name, g.type));
            return;
        }
        if (g.range > 0.0)
            addWarning(mScene,
                       fmt::format("{}: light '{}': range is ignored (inverse-square falloff)",
                                   mPath, g.name));
        l.origin = fmt::format("{}: KHR_lights_punctual lights[{}]", mPath, index);
        mScene.lights.push_back(l);
    }
};

}  // namespace

Scene loadGltfScene(const std::string& path) {
    Scene scene;
    scene.sourceFile = path;
    GltfLoader(scene, path).load();
    return scene;
}

}  // namespace loom::scene
