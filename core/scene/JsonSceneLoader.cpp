// Loom scene JSON (format documented in scenes/README.md). Every key is validated: an unknown
// key is an error naming file:line:col and listing the valid keys.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <set>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "core/image/Image.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneLoader.h"
#include "core/scene/Shapes.h"
#include "core/util/Error.h"
#include "core/util/JsonSource.h"
#include "core/util/Log.h"

namespace loom::scene {

namespace {

namespace fs = std::filesystem;

std::string escapeKey(const std::string& key) {
    std::string r;
    for (char c : key) {
        if (c == '~')
            r += "~0";
        else if (c == '/')
            r += "~1";
        else
            r += c;
    }
    return r;
}

std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

class JsonSceneLoader {
public:
    JsonSceneLoader(Scene& scene, const std::string& path)
        : mScene(scene),
          mSrc(JsonSource::load(path)),
          mDir(fs::path(path).parent_path().string()) {}

    void load() {
        const json& root = mSrc.root();
        if (!root.is_object()) fail("", "expected a JSON object at the top level");
        checkKeys(root, "", "scene",
                  {"loom_scene", "description", "camera", "textures", "materials", "shapes",
                   "lights", "environment"});
        if (root.contains("loom_scene")) {
            int version = integer(root, "", "loom_scene", 1);
            if (version != 1)
                fail("/loom_scene",
                     fmt::format("unsupported format version {} (expected 1)", version));
        }
        if (root.contains("description")) string(root, "", "description", "");
        if (root.contains("textures")) {
            const json& t = root["textures"];
            if (!t.is_object()) fail("/textures", "expected an object mapping names to textures");
            for (auto it = t.begin(); it != t.end(); ++it)
                mTextureNodes[it.key()] = "/textures/" + escapeKey(it.key());
        }
        if (root.contains("materials")) {
            const json& m = root["materials"];
            if (!m.is_object()) fail("/materials", "expected an object mapping names to materials");
            for (auto it = m.begin(); it != m.end(); ++it) {
                std::string ptr = "/materials/" + escapeKey(it.key());
                mMaterials[it.key()] = addMaterial(it.value(), ptr, it.key());
            }
        }
        if (!root.contains("shapes")) fail("", "missing key 'shapes'");
        const json& shapes = root["shapes"];
        if (!shapes.is_array() || shapes.empty())
            fail("/shapes", "expected a non-empty array of shapes");
        for (size_t i = 0; i < shapes.size(); ++i)
            addShape(shapes[i], fmt::format("/shapes/{}", i));
        if (root.contains("lights")) {
            const json& lights = root["lights"];
            if (!lights.is_array()) fail("/lights", "expected an array of lights");
            for (size_t i = 0; i < lights.size(); ++i)
                addLight(lights[i], fmt::format("/lights/{}", i));
        }
        if (root.contains("environment")) addEnvironment(root["environment"], "/environment");
        if (root.contains("camera")) {
            addCamera(root["camera"], "/camera");
        } else {
            detail::addWarning(
                mScene,
                mSrc.filename() + ": no camera; using a default camera in front of the scene");
            detail::setDefaultCamera(mScene);
        }
        // A scene that cannot emit light is warned about in detail::validateScene.
    }

private:
    Scene& mScene;
    JsonSource mSrc;
    std::string mDir;
    std::map<std::string, std::string> mTextureNodes;       // texture name -> JSON pointer
    std::map<std::pair<std::string, bool>, int> mTextures;  // (name, raw) -> Scene texture
    std::map<std::string, int> mMaterials;
    std::map<std::string, int> mMeshCache;
    int mDefaultMaterial = -1;

    // ---- diagnostics and typed access -----------------------------------------------------
    [[noreturn]] void fail(const std::string& ptr, const std::string& what) const {
        throw UserError(mSrc.where(ptr) + ": " + what);
    }
    static std::string child(const std::string& ptr, const std::string& key) {
        return ptr + "/" + escapeKey(key);
    }

    void checkKeys(const json& j, const std::string& ptr, const std::string& what,
                   const std::vector<std::string>& valid) const {
        for (auto it = j.begin(); it != j.end(); ++it)
            if (std::find(valid.begin(), valid.end(), it.key()) == valid.end())
                fail(child(ptr, it.key()), fmt::format("unknown key '{}' in {}; valid keys: {}",
                                                       it.key(), what, join(valid)));
    }
    const json* find(const json& j, const std::string& key) const {
        auto it = j.find(key);
        return it == j.end() ? nullptr : &*it;
    }
    float number(const json& j, const std::string& ptr, const std::string& key, float def) const {
        const json* v = find(j, key);
        if (!v) return def;
        if (!v->is_number()) fail(child(ptr, key), "'" + key + "' must be a number");
        return v->get<float>();
    }
    int integer(const json& j, const std::string& ptr, const std::string& key, int def) const {
        const json* v = find(j, key);
        if (!v) return def;
        if (!v->is_number_integer()) fail(child(ptr, key), "'" + key + "' must be an integer");
        int64_t x = v->get<int64_t>();
        if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max())
            fail(child(ptr, key), fmt::format("'{}' = {} does not fit a 32-bit integer", key, x));
        return int(x);
    }
    bool boolean(const json& j, const std::string& ptr, const std::string& key, bool def) const {
        const json* v = find(j, key);
        if (!v) return def;
        if (!v->is_boolean()) fail(child(ptr, key), "'" + key + "' must be true or false");
        return v->get<bool>();
    }
    std::string string(const json& j, const std::string& ptr, const std::string& key,
                       const std::string& def) const {
        const json* v = find(j, key);
        if (!v) return def;
        if (!v->is_string()) fail(child(ptr, key), "'" + key + "' must be a string");
        return v->get<std::string>();
    }
    std::vector<float> numbers(const json& v, const std::string& ptr, size_t n,
                               const std::string& key) const {
        if (!v.is_array() || v.size() != n)
            fail(ptr, fmt::format("'{}' must be an array of {} numbers", key, n));
        std::vector<float> r;
        for (size_t i = 0; i < n; ++i) {
            if (!v[i].is_number())
                fail(fmt::format("{}/{}", ptr, i),
                     fmt::format("'{}' must be an array of {} numbers", key, n));
            r.push_back(v[i].get<float>());
        }
        return r;
    }
    glm::vec3 vec3(const json& j, const std::string& ptr, const std::string& key,
                   const glm::vec3& def) const {
        const json* v = find(j, key);
        if (!v) return def;
        std::vector<float> r = numbers(*v, child(ptr, key), 3, key);
        return {r[0], r[1], r[2]};
    }
    glm::vec3 requiredVec3(const json& j, const std::string& ptr, const std::string& key) const {
        if (!find(j, key)) fail(ptr, "missing key '" + key + "'");
        return vec3(j, ptr, key, glm::vec3(0.0f));
    }
    // A colour: a number (grey) or [r, g, b].
    glm::vec3 color(const json& j, const std::string& ptr, const std::string& key,
                    const glm::vec3& def) const {
        const json* v = find(j, key);
        if (!v) return def;
        if (v->is_number()) return glm::vec3(v->get<float>());
        if (v->is_array() && v->size() == 3) return vec3(j, ptr, key, def);
        fail(child(ptr, key), "'" + key + "' must be a number or [r, g, b]");
    }
    glm::vec2 vec2OrScalar(const json& j, const std::string& ptr, const std::string& key,
                           glm::vec2 def) const {
        const json* v = find(j, key);
        if (!v) return def;
        if (v->is_number()) return glm::vec2(v->get<float>());
        std::vector<float> r = numbers(*v, child(ptr, key), 2, key);
        return {r[0], r[1]};
    }
    std::string file(const json& j, const std::string& ptr, const std::string& key) const {
        std::string f = string(j, ptr, key, "");
        if (f.empty()) fail(ptr, "missing key '" + key + "'");
        return detail::resolvePath(mDir, f);
    }

    // Per-frame rigid motion keyframes: {"time", "translate", "rotate", "scale"}.
    std::vector<ShapeKeyframe> shapePath(const json& path, const std::string& pp) const {
        if (!path.is_array() || path.empty())
            fail(pp, "'path' must be a non-empty array of keyframes");
        std::vector<ShapeKeyframe> out;
        for (size_t i = 0; i < path.size(); ++i) {
            const json& k = path[i];
            std::string kp = fmt::format("{}/{}", pp, i);
            if (!k.is_object()) fail(kp, "a keyframe must be an object");
            checkKeys(k, kp, "shape keyframe", {"time", "translate", "rotate", "scale"});
            if (!find(k, "time")) fail(kp, "missing key 'time'");
            ShapeKeyframe kf;
            kf.time = number(k, kp, "time", 0.0f);
            kf.translate = vec3(k, kp, "translate", glm::vec3(0.0f));
            if (const json* r = find(k, "rotate"))
                kf.rotate = glm::quat_cast(glm::mat3(transformOp({{"rotate", *r}}, kp)));
            if (const json* sc = find(k, "scale")) {
                std::string sp = child(kp, "scale");
                if (sc->is_number()) {
                    kf.scale = glm::vec3(sc->get<float>());
                } else {
                    std::vector<float> v = numbers(*sc, sp, 3, "scale");
                    kf.scale = glm::vec3(v[0], v[1], v[2]);
                }
                if (kf.scale.x == 0.0f || kf.scale.y == 0.0f || kf.scale.z == 0.0f)
                    fail(sp, "a keyframe scale must not be zero");
            }
            if (!out.empty() && kf.time <= out.back().time)
                fail(child(kp, "time"), "keyframe times must increase");
            out.push_back(kf);
        }
        return out;
    }

    // ---- transforms -------------------------------------------------------------------------
    // An array of operations applied first to last (Mitsuba order), or a single operation.
    glm::mat4 transform(const json& v, const std::string& ptr) const {
        if (v.is_object()) return transformOp(v, ptr);
        if (!v.is_array()) fail(ptr, "a transform must be an operation object or an array of them");
        glm::mat4 m(1.0f);
        for (size_t i = 0; i < v.size(); ++i)
            m = transformOp(v[i], fmt::format("{}/{}", ptr, i)) * m;
        return m;
    }
    glm::mat4 transformOp(const json& op, const std::string& ptr) const {
        static const std::vector<std::string> kOps = {"translate", "scale", "rotate", "matrix",
                                                      "lookat"};
        if (!op.is_object() || op.size() != 1)
            fail(ptr, "a transform operation is an object with exactly one key: " + join(kOps));
        const std::string key = op.begin().key();
        const json& v = op.begin().value();
        std::string p = child(ptr, key);
        if (key == "translate") {
            std::vector<float> t = numbers(v, p, 3, key);
            return glm::translate(glm::mat4(1.0f), glm::vec3(t[0], t[1], t[2]));
        }
        if (key == "scale") {
            if (v.is_number()) return glm::scale(glm::mat4(1.0f), glm::vec3(v.get<float>()));
            std::vector<float> s = numbers(v, p, 3, key);
            return glm::scale(glm::mat4(1.0f), glm::vec3(s[0], s[1], s[2]));
        }
        if (key == "rotate") {
            if (!v.is_object())
                fail(p, "'rotate' must be {\"axis\": [x, y, z], \"angle\": degrees}");
            checkKeys(v, p, "rotate", {"axis", "angle"});
            glm::vec3 axis = requiredVec3(v, p, "axis");
            if (glm::length(axis) == 0.0f) fail(child(p, "axis"), "rotation axis is zero");
            if (!find(v, "angle")) fail(p, "missing key 'angle'");
            return glm::rotate(glm::mat4(1.0f), glm::radians(number(v, p, "angle", 0.0f)),
                               glm::normalize(axis));
        }
        if (key == "matrix") {
            glm::mat4 m(1.0f);
            if (!v.is_array() || (v.size() != 16 && v.size() != 9))
                fail(p, "'matrix' must be 16 (4x4) or 9 (3x3) numbers, row-major");
            int n = v.size() == 16 ? 4 : 3;
            std::vector<float> a = numbers(v, p, v.size(), key);
            for (int r = 0; r < n; ++r)
                for (int c = 0; c < n; ++c) m[c][r] = a[size_t(r * n + c)];
            return m;
        }
        if (key == "lookat") {
            if (!v.is_object()) fail(p, "'lookat' must be {\"origin\", \"target\", \"up\"}");
            checkKeys(v, p, "lookat", {"origin", "target", "up"});
            glm::vec3 o = requiredVec3(v, p, "origin"), t = requiredVec3(v, p, "target");
            if (o == t) fail(p, "origin and target coincide");
            return lookAtMatrix(o, t, vec3(v, p, "up", glm::vec3(0, 1, 0)));
        }
        fail(child(ptr, key),
             fmt::format("unknown transform operation '{}'; valid: {}", key, join(kOps)));
    }

    // ---- textures and materials -------------------------------------------------------------
    int texture(const std::string& name, bool raw, const std::string& usePtr) {
        if (auto it = mTextures.find({name, raw}); it != mTextures.end()) return it->second;
        auto node = mTextureNodes.find(name);
        if (node == mTextureNodes.end()) {
            std::vector<std::string> names;
            for (auto& [k, v] : mTextureNodes) names.push_back(k);
            fail(usePtr, fmt::format("unknown texture '{}' (defined textures: {})", name,
                                     names.empty() ? "none" : join(names)));
        }
        const std::string& ptr = node->second;
        const json& t = mSrc.root().at(json::json_pointer(ptr));
        if (!t.is_object()) fail(ptr, "a texture must be an object");
        std::string type = string(t, ptr, "type", "");
        int index = -1;
        if (type == "bitmap") {
            checkKeys(t, ptr, "bitmap texture", {"type", "file", "raw", "uv_scale"});
            std::string path = file(t, ptr, "file");
            if (!fs::exists(path))
                fail(child(ptr, "file"), fmt::format("texture file not found: '{}'", path));
            index = detail::addBitmapTexture(mScene, path, boolean(t, ptr, "raw", raw),
                                             vec2OrScalar(t, ptr, "uv_scale", glm::vec2(1.0f)),
                                             mSrc.where(ptr));
            if (index < 0) fail(ptr, "cannot read texture '" + path + "'");
        } else if (type == "checkerboard") {
            checkKeys(t, ptr, "checkerboard texture", {"type", "color0", "color1", "uv_scale"});
            Texture tex;
            tex.name = name;
            tex.kind = TextureKind::Checkerboard;
            tex.color0 = color(t, ptr, "color0", glm::vec3(0.4f));
            tex.color1 = color(t, ptr, "color1", glm::vec3(0.2f));
            tex.uvScale = vec2OrScalar(t, ptr, "uv_scale", glm::vec2(1.0f));
            mScene.textures.push_back(tex);
            index = int(mScene.textures.size() - 1);
        } else {
            fail(child(ptr, "type"),
                 "texture type must be 'bitmap' or 'checkerboard', got '" + type + "'");
        }
        mTextures[{name, raw}] = index;
        return index;
    }
    // A colour, or a string naming a texture: returns the texture index (-1 for a colour).
    int colorOrTexture(const json& j, const std::string& ptr, const std::string& key,
                       glm::vec3& value) {
        const json* v = find(j, key);
        if (v && v->is_string()) {
            int tex = texture(v->get<std::string>(), false, child(ptr, key));
            value = detail::textureAverage(mScene.textures[size_t(tex)]);
            return tex;
        }
        value = color(j, ptr, key, value);
        return -1;
    }
    float ior(const json& j, const std::string& ptr, const std::string& key, float def) const {
        const json* v = find(j, key);
        if (!v) return def;
        if (v->is_string()) {
            float r = 1.0f;
            if (!detail::namedIor(v->get<std::string>(), r))
                fail(child(ptr, key),
                     "unknown IOR name '" + v->get<std::string>() + "' (e.g. water, bk7, diamond)");
            return r;
        }
        float r = number(j, ptr, key, def);
        if (!(r > 0.0f)) fail(child(ptr, key), "'ior' must be positive");
        return r;
    }

    int addMaterial(const json& j, const std::string& ptr, const std::string& name) {
        if (!j.is_object()) fail(ptr, "a material must be an object");
        std::string type = string(j, ptr, "type", "");
        static const std::map<std::string, BsdfType> kTypes = {
            {"diffuse", BsdfType::Diffuse},
            {"dielectric", BsdfType::Dielectric},
            {"roughdielectric", BsdfType::RoughDielectric},
            {"conductor", BsdfType::Conductor},
            {"roughconductor", BsdfType::RoughConductor},
            {"plastic", BsdfType::Plastic},
            {"roughplastic", BsdfType::RoughPlastic},
            {"null", BsdfType::Null}};
        auto it = kTypes.find(type);
        if (it == kTypes.end())
            fail(find(j, "type") ? child(ptr, "type") : ptr,
                 "material 'type' must be one of diffuse, dielectric, roughdielectric, conductor, "
                 "roughconductor, plastic, roughplastic, null; got '" +
                     type + "'");
        Material m;
        m.name = name;
        m.origin = mSrc.where(ptr);
        m.type = it->second;
        std::vector<std::string> keys = {"type", "two_sided", "normal_map"};
        bool rough =
            type == "roughdielectric" || type == "roughconductor" || type == "roughplastic";
        if (rough) keys.insert(keys.end(), {"alpha", "distribution"});
        if (type == "diffuse") keys.push_back("reflectance");
        if (type == "dielectric" || type == "roughdielectric")
            keys.insert(keys.end(), {"ior", "specular_reflectance", "specular_transmittance"});
        if (type == "conductor" || type == "roughconductor")
            keys.insert(keys.end(), {"metal", "eta", "k", "specular_reflectance"});
        if (type == "plastic" || type == "roughplastic")
            keys.insert(keys.end(), {"reflectance", "ior", "specular_reflectance", "nonlinear"});
        checkKeys(j, ptr, type + " material", keys);

        m.twoSided = boolean(j, ptr, "two_sided", false);
        if (rough) {
            m.alpha = number(j, ptr, "alpha", 0.1f);
            if (!(m.alpha > 0.0f)) fail(child(ptr, "alpha"), "'alpha' must be positive");
            std::string d = string(j, ptr, "distribution", "ggx");
            if (d == "ggx")
                m.distribution = Microfacet::GGX;
            else if (d == "beckmann")
                m.distribution = Microfacet::Beckmann;
            else
                fail(child(ptr, "distribution"), "'distribution' must be ggx or beckmann");
        }
        if (type == "diffuse" || type == "plastic" || type == "roughplastic")
            m.reflectanceTexture = colorOrTexture(j, ptr, "reflectance", m.reflectance);
        if (find(j, "specular_reflectance")) {
            m.specularReflectance = glm::vec3(1.0f);
            int tex = colorOrTexture(j, ptr, "specular_reflectance", m.specularReflectance);
            if (tex >= 0 && type != "conductor" && type != "roughconductor")
                fail(child(ptr, "specular_reflectance"),
                     "only conductors take a textured specular_reflectance");
            m.specularReflectanceTexture = tex;
        }
        m.specularTransmittance = color(j, ptr, "specular_transmittance", glm::vec3(1.0f));
        if (m.type == BsdfType::Dielectric || m.type == BsdfType::RoughDielectric)
            m.eta = ior(j, ptr, "ior", 1.5f);
        if (m.type == BsdfType::Plastic || m.type == BsdfType::RoughPlastic) {
            m.eta = ior(j, ptr, "ior", 1.5f);
            m.nonlinear = boolean(j, ptr, "nonlinear", false);
        }
        if (m.type == BsdfType::Conductor || m.type == BsdfType::RoughConductor) {
            if (find(j, "metal") && (find(j, "eta") || find(j, "k")))
                fail(ptr, "give either 'metal' or 'eta'/'k', not both");
            if (find(j, "eta") || find(j, "k")) {
                m.conductorEta = color(j, ptr, "eta", glm::vec3(0.0f));
                m.conductorK = color(j, ptr, "k", glm::vec3(1.0f));
            } else {
                std::string metal = string(j, ptr, "metal", "none");
                if (!detail::conductorIor(metal, m.conductorEta, m.conductorK))
                    fail(child(ptr, "metal"), fmt::format("unknown metal '{}' (known: {})", metal,
                                                          detail::conductorNames()));
            }
        }
        if (const json* nm = find(j, "normal_map")) {
            std::string p = child(ptr, "normal_map");
            if (nm->is_string()) {
                m.normalMap = texture(nm->get<std::string>(), true, p);
                m.normalMapUseSlopes = false;
            } else if (nm->is_object()) {
                checkKeys(*nm, p, "normal_map", {"file", "tiles", "use_slopes"});
                std::string path = file(*nm, p, "file");
                if (!fs::exists(path))
                    fail(child(p, "file"), fmt::format("normal map file not found: '{}'", path));
                m.normalMap = detail::addBitmapTexture(
                    mScene, path, true, glm::vec2(number(*nm, p, "tiles", 1.0f)), mSrc.where(p));
                if (m.normalMap < 0) fail(p, "cannot read normal map '" + path + "'");
                m.normalMapUseSlopes = boolean(*nm, p, "use_slopes", true);
            } else {
                fail(
                    p,
                    "'normal_map' must be a texture name or {\"file\", \"tiles\", \"use_slopes\"}");
            }
        }
        mScene.materials.push_back(m);
        return int(mScene.materials.size() - 1);
    }

    // ---- shapes -----------------------------------------------------------------------------
    int mesh(const std::string& key, const std::function<Mesh()>& make) {
        if (auto it = mMeshCache.find(key); it != mMeshCache.end()) return it->second;
        mScene.meshes.push_back(make());
        mMeshCache[key] = int(mScene.meshes.size() - 1);
        return mMeshCache[key];
    }

    void addShape(const json& j, const std::string& ptr) {
        if (!j.is_object()) fail(ptr, "a shape must be an object");
        std::string type = string(j, ptr, "type", "");
        std::vector<std::string> keys = {"name",
                                         "type",
                                         "material",
                                         "transform",
                                         "transform_end",
                                         "path",
                                         "emission",
                                         "caustic_caster",
                                         "caustic_receiver",
                                         "caustic_bouncer",
                                         "caustic_emitter",
                                         "caustic_multi",
                                         "visible_camera",
                                         "visible_shadow",
                                         "ray_mask",
                                         "flip_normals",
                                         "face_normals"};
        static const std::map<std::string, std::vector<std::string>> kTypeKeys = {
            {"mesh", {"file"}},
            {"rectangle", {}},
            {"cube", {}},
            {"sphere", {"center", "radius", "rings", "segments"}},
            {"disk", {"segments"}},
            {"cylinder", {"p0", "p1", "radius", "segments"}},
            {"heightfield", {"resolution", "height", "image", "height_scale"}},
            {"grass", {"blades", "seed", "height", "width", "bend"}}};
        auto tk = kTypeKeys.find(type);
        if (tk == kTypeKeys.end())
            fail(find(j, "type") ? child(ptr, "type") : ptr,
                 "shape 'type' must be one of mesh, rectangle, cube, sphere, disk, cylinder, "
                 "heightfield, grass; got '" +
                     type + "'");
        keys.insert(keys.end(), tk->second.begin(), tk->second.end());
        checkKeys(j, ptr, type + " shape", keys);

        Shape s;
        s.name = string(j, ptr, "name", fmt::format("{}{}", type, mScene.shapes.size()));
        if (const json* t = find(j, "transform"))
            s.toWorld = transform(*t, child(ptr, "transform"));
        if (const json* t = find(j, "transform_end")) {
            s.toWorldEnd = transform(*t, child(ptr, "transform_end"));
            s.moving = true;
        }
        if (const json* path = find(j, "path")) s.path = shapePath(*path, child(ptr, "path"));
        bool faceNormals = boolean(j, ptr, "face_normals", false);
        bool flip = boolean(j, ptr, "flip_normals", false);
        auto finish = [&](Mesh m) {
            if (faceNormals) {
                m.normals.clear();
                m.faceNormals = true;
            } else if (m.normals.empty()) {
                computeVertexNormals(m);
            }
            if (flip) flipNormals(m);
            return m;
        };
        std::string variant = fmt::format("|{}|{}", faceNormals, flip);
        auto segments = [&](const char* key, int def) {
            int n = integer(j, ptr, key, def);
            if (n < 3 || n > 4096)
                fail(child(ptr, key), fmt::format("'{}' must be in [3, 4096]", key));
            return uint32_t(n);
        };
        if (type == "mesh") {
            std::string path = file(j, ptr, "file");
            if (!fs::exists(path))
                fail(child(ptr, "file"), fmt::format("mesh file not found: '{}'", path));
            std::string ext = fs::path(path).extension().string();
            if (ext != ".obj" && ext != ".ply")
                fail(child(ptr, "file"), "mesh files must be .obj or .ply");
            s.mesh = mesh(path + variant, [&] {
                return finish(ext == ".obj" ? readObjMesh(path) : readPly(path));
            });
        } else if (type == "rectangle" || type == "cube") {
            s.mesh = mesh(type + variant, [&] {
                return finish(type == "rectangle" ? makeRectangle() : makeCube());
            });
        } else if (type == "sphere") {
            glm::vec3 center = vec3(j, ptr, "center", glm::vec3(0.0f));
            float radius = number(j, ptr, "radius", 1.0f);
            s.toWorld = s.toWorld * glm::translate(glm::mat4(1.0f), center) *
                        glm::scale(glm::mat4(1.0f), glm::vec3(radius));
            if (s.moving)
                s.toWorldEnd = s.toWorldEnd * glm::translate(glm::mat4(1.0f), center) *
                               glm::scale(glm::mat4(1.0f), glm::vec3(radius));
            uint32_t rings = segments("rings", 32), segs = segments("segments", 64);
            s.mesh = mesh(fmt::format("sphere{}x{}{}", rings, segs, variant),
                          [&] { return finish(makeSphere(rings, segs)); });
        } else if (type == "disk") {
            uint32_t segs = segments("segments", 64);
            s.mesh = mesh(fmt::format("disk{}{}", segs, variant),
                          [&] { return finish(makeDisk(segs)); });
        } else if (type == "cylinder") {
            glm::vec3 p0 = vec3(j, ptr, "p0", glm::vec3(0.0f)),
                      p1 = vec3(j, ptr, "p1", glm::vec3(0, 0, 1));
            if (p0 == p1) fail(ptr, "p0 and p1 coincide");
            glm::mat4 c = cylinderTransform(p0, p1, number(j, ptr, "radius", 1.0f));
            s.toWorld = s.toWorld * c;
            if (s.moving) s.toWorldEnd = s.toWorldEnd * c;
            uint32_t segs = segments("segments", 64);
            s.mesh = mesh(fmt::format("cylinder{}{}", segs, variant),
                          [&] { return finish(makeCylinder(segs)); });
        } else if (type == "heightfield") {
            s.mesh = int(mScene.meshes.size());
            mScene.meshes.push_back(finish(heightfield(j, ptr, &s.deformation)));
            mScene.meshes.back().name = s.name;
            if (s.deformation)  // the same finishing (face normals, flips) every frame
                s.deformation = [d = s.deformation, faceNormals, flip](float t) {
                    Mesh m = d(t);
                    if (faceNormals) {
                        m.normals.clear();
                        m.faceNormals = true;
                    }
                    if (flip) flipNormals(m);
                    return m;
                };
        } else if (type == "grass") {
            GrassParams g;
            int blades = integer(j, ptr, "blades", 500);
            if (blades < 1 || blades > 1000000)
                fail(child(ptr, "blades"),
                     fmt::format("'blades' = {} must be in [1, 1000000]", blades));
            g.blades = uint32_t(blades);
            g.seed = uint32_t(integer(j, ptr, "seed", 1));
            if (find(j, "height")) {
                std::vector<float> h = numbers(j["height"], child(ptr, "height"), 2, "height");
                g.minHeight = h[0];
                g.maxHeight = h[1];
            }
            g.width = number(j, ptr, "width", g.width);
            g.bend = number(j, ptr, "bend", g.bend);
            s.mesh = int(mScene.meshes.size());
            Mesh m = makeGrass(g);
            m.name = s.name;
            if (flip) flipNormals(m);
            mScene.meshes.push_back(std::move(m));  // flat shaded thin blades
        }

        // Material: a name, an inline object, or the default grey diffuse.
        if (const json* mat = find(j, "material")) {
            std::string p = child(ptr, "material");
            if (mat->is_string()) {
                auto it = mMaterials.find(mat->get<std::string>());
                if (it == mMaterials.end()) {
                    std::vector<std::string> names;
                    for (auto& [k, v] : mMaterials) names.push_back(k);
                    fail(p, fmt::format("unknown material '{}' (defined materials: {})",
                                        mat->get<std::string>(),
                                        names.empty() ? "none" : join(names)));
                }
                s.material = it->second;
            } else {
                s.material = addMaterial(*mat, p, s.name);
            }
        } else {
            if (mDefaultMaterial < 0) {
                mScene.materials.push_back(Material{});
                mScene.materials.back().name = "default";
                mDefaultMaterial = int(mScene.materials.size() - 1);
            }
            s.material = mDefaultMaterial;
        }
        s.emission = color(j, ptr, "emission", glm::vec3(0.0f));
        if (s.emission.x < 0 || s.emission.y < 0 || s.emission.z < 0)
            fail(child(ptr, "emission"), "emission must be >= 0");

        // Flags.
        s.flags = 0;
        if (boolean(j, ptr, "visible_camera", true)) s.flags |= kVisibleCamera;
        if (boolean(j, ptr, "visible_shadow", true)) s.flags |= kVisibleShadow;
        if (boolean(j, ptr, "caustic_caster", false)) {
            BsdfType t = mScene.materials[size_t(s.material)].type;
            if (t == BsdfType::Dielectric || t == BsdfType::RoughDielectric)
                s.flags |= kCausticCasterRefract;
            else if (t == BsdfType::Conductor || t == BsdfType::RoughConductor)
                s.flags |= kCausticCasterReflect;
            else
                fail(child(ptr, "caustic_caster"),
                     "caustic casters need a dielectric or conductor material");
        }
        if (boolean(j, ptr, "caustic_receiver", false)) s.flags |= kCausticReceiver;
        if (boolean(j, ptr, "caustic_bouncer", false)) s.flags |= kCausticBouncer;
        if (boolean(j, ptr, "caustic_emitter", false)) {
            if (glm::length(s.emission) == 0.0f)
                fail(child(ptr, "caustic_emitter"), "caustic_emitter needs an emission");
            s.flags |= kCausticEmitter;
        }
        if (boolean(j, ptr, "caustic_multi", false)) s.flags |= kCausticMulti;
        int mask = integer(j, ptr, "ray_mask", 0xff);
        if (mask < 0 || mask > 0xff) fail(child(ptr, "ray_mask"), "'ray_mask' must be in [0, 255]");
        s.rayMask = uint32_t(mask);
        s.origin = mSrc.where(ptr);
        mScene.shapes.push_back(s);
    }

    // A formula that reads t also gives the per-frame mesh (an animated surface).
    Mesh heightfield(const json& j, const std::string& ptr,
                     std::function<Mesh(float)>* deformation) {
        glm::uvec2 res(64);
        if (const json* r = find(j, "resolution")) {
            if (r->is_number_integer())
                res = glm::uvec2(uint32_t(std::max(r->get<int>(), 0)));
            else {
                std::vector<float> v = numbers(*r, child(ptr, "resolution"), 2, "resolution");
                res = {uint32_t(std::max(v[0], 0.0f)), uint32_t(std::max(v[1], 0.0f))};
            }
            if (res.x < 1 || res.y < 1 || res.x > 4096 || res.y > 4096)
                fail(child(ptr, "resolution"), "'resolution' must be in [1, 4096]");
        }
        float scale = number(j, ptr, "height_scale", 1.0f);
        bool hasFormula = find(j, "height"), hasImage = find(j, "image");
        if (hasFormula == hasImage)
            fail(ptr, "a heightfield needs exactly one of 'height' (formula) or 'image'");
        if (hasFormula) {
            std::string text = string(j, ptr, "height", "");
            HeightFormula f = HeightFormula::parse(text, mSrc.where(child(ptr, "height")));
            // t = 0 here; SceneGpu tessellates an animated one at each frame's time.
            Mesh m = makeHeightfield(res.x, res.y,
                                     [&](float x, float y) { return scale * f(x, y, 0.0f); });
            if (f.usesTime()) {
                const std::string name = string(j, ptr, "name", "");
                *deformation = [f, res, scale, name](float t) {
                    Mesh d = makeHeightfield(res.x, res.y,
                                             [&](float x, float y) { return scale * f(x, y, t); });
                    d.name = name;
                    for (const glm::vec3& p : d.positions)
                        if (!std::isfinite(p.z))
                            throw UserError(fmt::format(
                                "heightfield '{}': formula is not finite at x = {}, y = {}, t = {}",
                                name, p.x, p.y, t));
                    return d;
                };
            }
            for (const glm::vec3& p : m.positions)
                if (!std::isfinite(p.z))
                    fail(child(ptr, "height"),
                         fmt::format("formula is not finite at x = {}, y = {}", p.x, p.y));
            return m;
        }
        std::string path = file(j, ptr, "image");
        if (!fs::exists(path))
            fail(child(ptr, "image"), fmt::format("height image not found: '{}'", path));
        ImageData img = readImage(path, false);
        // Bilinear lookup of the luminance (first channel for grey images), uv as the mesh's.
        auto lum = [&](uint32_t x, uint32_t y) {
            if (img.channels < 3) return img.at(x, y, 0);
            return 0.2126f * img.at(x, y, 0) + 0.7152f * img.at(x, y, 1) +
                   0.0722f * img.at(x, y, 2);
        };
        return makeHeightfield(res.x, res.y, [&](float x, float y) {
            float u = (x + 1.0f) * 0.5f * float(img.width - 1),
                  v = (y + 1.0f) * 0.5f * float(img.height - 1);
            auto x0 = uint32_t(std::floor(u)), y0 = uint32_t(std::floor(v));
            uint32_t x1 = std::min(x0 + 1, img.width - 1), y1 = std::min(y0 + 1, img.height - 1);
            float fx = u - float(x0), fy = v - float(y0);
            float h = (1 - fx) * (1 - fy) * lum(x0, y0) + fx * (1 - fy) * lum(x1, y0) +
                      (1 - fx) * fy * lum(x0, y1) + fx * fy * lum(x1, y1);
            return scale * h;
        });
    }

    // ---- lights -----------------------------------------------------------------------------
    void addLight(const json& j, const std::string& ptr) {
        if (!j.is_object()) fail(ptr, "a light must be an object");
        std::string type = string(j, ptr, "type", "");
        Light l;
        if (type == "point") {
            checkKeys(j, ptr, "point light", {"type", "position", "intensity", "caustic_emitter"});
            l.type = LightType::Point;
            l.position = requiredVec3(j, ptr, "position");
            l.intensity = color(j, ptr, "intensity", glm::vec3(1.0f));
            l.toWorld = glm::translate(glm::mat4(1.0f), l.position);
        } else if (type == "spot") {
            checkKeys(j, ptr, "spot light",
                      {"type", "position", "target", "direction", "intensity", "cutoff_angle",
                       "beam_width", "caustic_emitter"});
            l.type = LightType::Spot;
            l.position = requiredVec3(j, ptr, "position");
            if (find(j, "target") == find(j, "direction") ||
                (find(j, "target") && find(j, "direction")))
                fail(ptr, "a spot light needs exactly one of 'target' or 'direction'");
            glm::vec3 dir = find(j, "target") ? vec3(j, ptr, "target", {}) - l.position
                                              : vec3(j, ptr, "direction", {});
            if (glm::length(dir) == 0.0f) fail(ptr, "spot direction is zero");
            l.direction = glm::normalize(dir);
            l.intensity = color(j, ptr, "intensity", glm::vec3(1.0f));
            l.cutoffAngle = number(j, ptr, "cutoff_angle", 20.0f);
            l.beamWidth = number(j, ptr, "beam_width", 0.75f * l.cutoffAngle);
            if (!(l.cutoffAngle > 0.0f && l.cutoffAngle <= 90.0f))
                fail(child(ptr, "cutoff_angle"), "must be in (0, 90]");
            l.toWorld = lookAtMatrix(
                l.position, l.position + l.direction,
                std::fabs(l.direction.y) < 0.99f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0));
        } else if (type == "directional") {
            checkKeys(j, ptr, "directional light",
                      {"type", "direction", "irradiance", "caustic_emitter"});
            l.type = LightType::Directional;
            glm::vec3 d = requiredVec3(j, ptr, "direction");
            if (glm::length(d) == 0.0f) fail(child(ptr, "direction"), "direction is zero");
            l.direction = glm::normalize(d);
            l.intensity = color(j, ptr, "irradiance", glm::vec3(1.0f));
        } else if (type == "envmap") {
            checkKeys(j, ptr, "envmap light",
                      {"type", "file", "scale", "transform", "caustic_emitter"});
            envmap(j, ptr, l);
        } else if (type == "constant") {
            checkKeys(j, ptr, "constant light", {"type", "radiance", "caustic_emitter"});
            l.type = LightType::Constant;
            l.intensity = color(j, ptr, "radiance", glm::vec3(1.0f));
        } else {
            fail(find(j, "type") ? child(ptr, "type") : ptr,
                 "light 'type' must be point, spot, directional, envmap or constant (area lights "
                 "are "
                 "shapes with an 'emission'); got '" +
                     type + "'");
        }
        if (boolean(j, ptr, "caustic_emitter", false)) l.flags |= kCausticEmitter;
        l.origin = mSrc.where(ptr);
        mScene.lights.push_back(l);
    }
    void envmap(const json& j, const std::string& ptr, Light& l) {
        l.type = LightType::Environment;
        std::string path = file(j, ptr, "file");
        if (!fs::exists(path))
            fail(child(ptr, "file"), fmt::format("environment map not found: '{}'", path));
        l.envTexture =
            detail::addBitmapTexture(mScene, path, false, glm::vec2(1.0f), mSrc.where(ptr));
        if (l.envTexture < 0) fail(ptr, "cannot read environment map '" + path + "'");
        l.scale = number(j, ptr, "scale", 1.0f);
        if (const json* t = find(j, "transform"))
            l.toWorld = transform(*t, child(ptr, "transform"));
    }
    void addEnvironment(const json& j, const std::string& ptr) {
        if (!j.is_object())
            fail(ptr,
                 "'environment' must be {\"file\", \"scale\", \"transform\"} or {\"radiance\"}");
        Light l;
        if (find(j, "radiance")) {
            checkKeys(j, ptr, "environment", {"radiance"});
            l.type = LightType::Constant;
            l.intensity = color(j, ptr, "radiance", glm::vec3(1.0f));
        } else {
            checkKeys(j, ptr, "environment", {"file", "scale", "transform"});
            envmap(j, ptr, l);
        }
        l.origin = mSrc.where(ptr);
        mScene.lights.push_back(l);
    }

    // ---- camera -----------------------------------------------------------------------------
    void addCamera(const json& j, const std::string& ptr) {
        if (!j.is_object()) fail(ptr, "'camera' must be an object");
        checkKeys(j, ptr, "camera",
                  {"type", "origin", "target", "up", "transform", "fov", "aperture_radius",
                   "focus_distance", "shutter", "film", "path"});
        Camera& c = mScene.camera;
        c = Camera{};
        std::string type = string(j, ptr, "type", "pinhole");
        if (type == "thin_lens") {
            c.type = CameraType::ThinLens;
            c.apertureRadius = number(j, ptr, "aperture_radius", 0.05f);
            c.focusDistance = number(j, ptr, "focus_distance", 1.0f);
            if (!(c.focusDistance > 0.0f)) fail(child(ptr, "focus_distance"), "must be positive");
            if (c.apertureRadius < 0.0f) fail(child(ptr, "aperture_radius"), "must be >= 0");
        } else if (type != "pinhole") {
            fail(child(ptr, "type"),
                 "camera 'type' must be pinhole or thin_lens, got '" + type + "'");
        } else if (find(j, "aperture_radius") || find(j, "focus_distance")) {
            fail(ptr, "aperture_radius/focus_distance need \"type\": \"thin_lens\"");
        }
        // The Loom fov is vertical.
        c.fovAxis = Camera::FovAxis::Y;
        c.fov = number(j, ptr, "fov", 40.0f);
        if (!(c.fov > 0.0f && c.fov < 180.0f))
            fail(child(ptr, "fov"), "'fov' must be in (0, 180) degrees");
        glm::vec3 origin(0, 0, 5), target(0), up(0, 1, 0);
        if (find(j, "transform")) {
            if (find(j, "origin") || find(j, "target") || find(j, "up"))
                fail(ptr, "give either 'transform' or 'origin'/'target'/'up', not both");
            c.toWorld = transform(j["transform"], child(ptr, "transform"));
        } else {
            origin = requiredVec3(j, ptr, "origin");
            target = requiredVec3(j, ptr, "target");
            up = vec3(j, ptr, "up", up);
            if (origin == target) fail(ptr, "camera origin and target coincide");
            c.toWorld = lookAtMatrix(origin, target, up);
        }
        if (const json* s = find(j, "shutter")) {
            std::vector<float> v = numbers(*s, child(ptr, "shutter"), 2, "shutter");
            if (v[1] < v[0]) fail(child(ptr, "shutter"), "shutter close must not precede open");
            c.shutterOpen = v[0];
            c.shutterClose = v[1];
        }
        if (const json* f = find(j, "film")) {
            std::vector<float> v = numbers(*f, child(ptr, "film"), 2, "film");
            if (v[0] < 1 || v[1] < 1) fail(child(ptr, "film"), "film size must be positive");
            c.filmWidth = uint32_t(v[0]);
            c.filmHeight = uint32_t(v[1]);
        }
        if (const json* path = find(j, "path")) {
            std::string pp = child(ptr, "path");
            if (!path->is_array() || path->empty())
                fail(pp, "'path' must be a non-empty array of keyframes");
            if (find(j, "transform"))
                fail(pp, "a camera path needs origin/target/up, not 'transform'");
            for (size_t i = 0; i < path->size(); ++i) {
                const json& k = (*path)[i];
                std::string kp = fmt::format("{}/{}", pp, i);
                if (!k.is_object()) fail(kp, "a keyframe must be an object");
                checkKeys(k, kp, "keyframe", {"time", "origin", "target", "up", "fov"});
                if (!find(k, "time")) fail(kp, "missing key 'time'");
                CameraKeyframe kf;
                kf.time = number(k, kp, "time", 0.0f);
                kf.origin = vec3(k, kp, "origin", origin);
                kf.target = vec3(k, kp, "target", target);
                kf.up = vec3(k, kp, "up", up);
                kf.fovY = number(k, kp, "fov", c.fov);
                if (!c.path.empty() && kf.time <= c.path.back().time)
                    fail(child(kp, "time"), "keyframe times must increase");
                if (kf.origin == kf.target) fail(kp, "keyframe origin and target coincide");
                c.path.push_back(kf);
            }
        }
    }
};

}  // namespace

Scene loadJsonScene(const std::string& path) {
    Scene scene;
    scene.sourceFile = path;
    JsonSceneLoader(scene, path).load();
    return scene;
}

}  // namespace loom::scene
