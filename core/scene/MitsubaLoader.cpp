// Mitsuba scene loader (XML versions 0.5/0.6, 2 and 3) for the subset Loom renders.
// pugixml stays private to this file.
//
// Processing order: parse -> (0.x only) normalise camelCase names -> collect <default> values ->
// substitute $variables in every attribute -> index every element with an id -> build objects.
// Objects with an id (bsdfs, textures, films) are built when first referenced and cached.
// Every plugin element's properties are tracked; properties Loom does not read produce one
// warning each (or a debug line for ones that do not affect the image, e.g. near_clip).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>
#include <pugixml.hpp>

#include "core/scene/Camera.h"
#include "core/scene/SceneLoader.h"
#include "core/scene/Shapes.h"
#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom::scene {

namespace {

namespace fs = std::filesystem;
using detail::addWarning;

// One parsed XML file (the scene or an <include>d file) with its line index.
struct XmlFile {
    std::string path, dir, text;
    std::vector<size_t> lineStarts;  // byte offset of each line start
    pugi::xml_document doc;
    int majorVersion = 3;

    int line(ptrdiff_t offset) const {
        if (offset < 0) return 0;
        auto it = std::upper_bound(lineStarts.begin(), lineStarts.end(), size_t(offset));
        return int(it - lineStarts.begin());
    }
    int column(ptrdiff_t offset) const {
        int l = line(offset);
        return l > 0 ? int(size_t(offset) - lineStarts[l - 1]) + 1 : 0;
    }
};

// "intIOR" -> "int_ior", "toWorld" -> "to_world" (Mitsuba 0.5/0.6 -> 2/3 names).
std::string camelToSnake(const std::string& s) {
    std::string r;
    for (size_t i = 0; i < s.size(); ++i) {
        char c = s[i];
        bool upper = std::isupper(static_cast<unsigned char>(c));
        if (upper && i > 0 &&
            (std::islower(static_cast<unsigned char>(s[i - 1])) ||
             std::isdigit(static_cast<unsigned char>(s[i - 1]))))
            r += '_';
        r += char(std::tolower(static_cast<unsigned char>(c)));
    }
    return r;
}

std::string toLower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

bool isPropertyTag(const std::string& tag) {
    static const std::set<std::string> kTags = {"float",  "integer",   "boolean",   "string",
                                                "rgb",    "srgb",      "spectrum",  "point",
                                                "vector", "transform", "blackbody", "animation"};
    return kTags.count(tag) > 0;
}

bool isObjectTag(const std::string& tag) {
    static const std::set<std::string> kTags = {
        "bsdf", "emitter", "texture", "ref",   "medium", "shape",      "sensor",
        "film", "sampler", "rfilter", "phase", "volume", "integrator", "subsurface"};
    return kTags.count(tag) > 0;
}

struct ColorTex {
    glm::vec3 value{0.0f};
    int texture = -1;
};

class MitsubaLoader;

// The properties and nested objects of one plugin element, with use tracking.
class Props {
public:
    Props(MitsubaLoader& loader, pugi::xml_node plugin);

    pugi::xml_node node() const { return mNode; }
    bool has(const std::string& name) const { return mNamed.count(name) > 0; }
    // The property element (marked as used), or an empty node.
    pugi::xml_node get(const std::string& name);

    float getFloat(const std::string& name, float def);
    int getInt(const std::string& name, int def);
    bool getBool(const std::string& name, bool def);
    std::string getString(const std::string& name, const std::string& def);
    glm::vec3 getVector(const std::string& name, const glm::vec3& def);
    glm::mat4 getTransform(const std::string& name);
    // Colour; a texture here is replaced by its mean with a warning.
    glm::vec3 getColor(const std::string& name, const glm::vec3& def);
    ColorTex getColorTex(const std::string& name, const glm::vec3& def, bool raw = false);
    // A float that may also be given as an IOR name (<string name="int_ior" value="bk7"/>).
    float getIor(const std::string& name, float def);

    // Unnamed nested objects (<bsdf>, <emitter>, <ref id>, ...), in document order.
    const std::vector<pugi::xml_node>& objects() const { return mObjects; }
    // One warning per property nobody read; names in `quiet` only get a debug line.
    void reportUnused(std::initializer_list<const char*> quiet = {});

private:
    MitsubaLoader& mLoader;
    pugi::xml_node mNode;
    std::map<std::string, pugi::xml_node> mNamed;
    std::set<std::string> mUsed;
    std::vector<pugi::xml_node> mObjects;
};

class MitsubaLoader {
public:
    MitsubaLoader(Scene& scene, const std::map<std::string, std::string>& defines)
        : mScene(scene), mDefaults(defines) {}

    void load(const std::string& path) {
        mIncludeStack = {fs::weakly_canonical(path).string()};
        XmlFile& file = parseFile(path);
        pugi::xml_node root = file.doc.document_element();
        if (std::string(root.name()) != "scene") fail(root, "expected <scene> as the root element");
        processChildren(root);
        if (!mHaveCamera) {
            addWarning(mScene,
                       path + ": no <sensor>; using a default camera in front of the scene");
            detail::setDefaultCamera(mScene);
        }
    }

    // ---- diagnostics ------------------------------------------------------------------------
    const XmlFile& fileOf(pugi::xml_node node) const {
        pugi::xml_node root = node.root();
        for (const auto& f : mFiles)
            if (f->doc == root) return *f;
        return *mFiles.front();
    }
    std::string where(pugi::xml_node node) const {
        const XmlFile& f = fileOf(node);
        int line = f.line(node.offset_debug());
        return line > 0 ? fmt::format("{}:{}", f.path, line) : f.path;
    }
    static std::string describe(pugi::xml_node node) {
        std::string s = "<" + std::string(node.name());
        for (const char* a : {"type", "name", "id"})
            if (node.attribute(a)) s += fmt::format(" {}=\"{}\"", a, node.attribute(a).value());
        return s + ">";
    }
    [[noreturn]] void fail(pugi::xml_node node, const std::string& what) const {
        throw UserError(fmt::format("{}: {}: {}", where(node), describe(node), what));
    }
    void warn(pugi::xml_node node, const std::string& what) {
        addWarning(mScene, fmt::format("{}: {}: {}", where(node), describe(node), what));
    }
    void debug(pugi::xml_node node, const std::string& what) {
        logDebug("{}: {}: {}", where(node), describe(node), what);
    }

    // ---- value parsing ----------------------------------------------------------------------
    std::vector<float> parseNumbers(pugi::xml_node node, const char* attr) {
        std::string text = node.attribute(attr).value();
        std::vector<float> values;
        const char* p = text.c_str();
        while (*p) {
            while (*p && (std::isspace(static_cast<unsigned char>(*p)) || *p == ',')) ++p;
            if (!*p) break;
            char* end = nullptr;
            float v = std::strtof(p, &end);
            if (end == p)
                fail(node, fmt::format("attribute '{}': expected numbers, got '{}'", attr, text));
            values.push_back(v);
            p = end;
        }
        return values;
    }
    float parseNumber(pugi::xml_node node, const char* attr) {
        if (!node.attribute(attr)) fail(node, fmt::format("missing attribute '{}'", attr));
        std::vector<float> v = parseNumbers(node, attr);
        if (v.size() != 1)
            fail(node, fmt::format("attribute '{}': expected one number, got '{}'", attr,
                                   node.attribute(attr).value()));
        return v[0];
    }
    // value="x, y, z" or x="" y="" z="" attributes (missing components = def).
    glm::vec3 parseVec3(pugi::xml_node node, float def) {
        if (node.attribute("value")) {
            std::vector<float> v = parseNumbers(node, "value");
            if (v.size() == 1) return glm::vec3(v[0]);
            if (v.size() != 3)
                fail(node, fmt::format("attribute 'value': expected 1 or 3 numbers, got '{}'",
                                       node.attribute("value").value()));
            return {v[0], v[1], v[2]};
        }
        glm::vec3 r(def);
        const char* names[3] = {"x", "y", "z"};
        for (int i = 0; i < 3; ++i)
            if (node.attribute(names[i])) r[i] = parseNumber(node, names[i]);
        return r;
    }
    glm::vec3 parseColorElement(pugi::xml_node node) {
        std::string tag = node.name();
        std::string value = node.attribute("value").value();
        if (tag == "float" || tag == "integer") return glm::vec3(parseNumber(node, "value"));
        if (!node.attribute("value")) {
            if (tag == "spectrum" && node.attribute("filename")) {
                warn(node, "spectral data files are not supported; using 0.5 grey instead");
                return glm::vec3(0.5f);
            }
            fail(node, "missing attribute 'value'");
        }
        auto srgbDecode = [](float v) {
            return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
        };
        if (!value.empty() && value[0] == '#') {  // "#rrggbb", sRGB encoded
            if (value.size() != 7 || !std::all_of(value.begin() + 1, value.end(), [](char ch) {
                    return std::isxdigit(static_cast<unsigned char>(ch));
                }))
                fail(node, "expected a colour '#rrggbb' (hex digits), got '" + value + "'");
            glm::vec3 c;
            for (int i = 0; i < 3; ++i)
                c[i] = srgbDecode(
                    float(std::strtol(value.substr(1 + 2 * i, 2).c_str(), nullptr, 16)) / 255.0f);
            return c;
        }
        if (tag == "rgb" || tag == "srgb") {
            std::vector<float> v = parseNumbers(node, "value");
            glm::vec3 c;
            if (v.size() == 1)
                c = glm::vec3(v[0]);
            else if (v.size() == 3)
                c = {v[0], v[1], v[2]};
            else
                fail(node, "attribute 'value': expected 1 or 3 numbers, got '" + value + "'");
            if (tag == "srgb") c = {srgbDecode(c.x), srgbDecode(c.y), srgbDecode(c.z)};
            return c;
        }
        if (tag == "spectrum") {
            if (value.find(':') == std::string::npos) {
                std::vector<float> v = parseNumbers(node, "value");
                if (v.size() == 1) return glm::vec3(v[0]);
                if (v.size() == 3) return {v[0], v[1], v[2]};
                fail(node, "attribute 'value': expected a number or 'wavelength:value' pairs");
            }
            // "400:0.1, 500:0.3, ...": mean over the visible samples.
            double sum = 0.0;
            int count = 0;
            std::stringstream ss(value);
            std::string item;
            while (std::getline(ss, item, ',')) {
                auto colon = item.find(':');
                if (colon == std::string::npos)
                    fail(node, "malformed 'wavelength:value' pair '" + item + "'");
                float lambda = std::strtof(item.substr(0, colon).c_str(), nullptr);
                float v = std::strtof(item.substr(colon + 1).c_str(), nullptr);
                if (lambda >= 380.0f && lambda <= 780.0f) {
                    sum += v;
                    ++count;
                }
            }
            warn(node, "spectral samples approximated by their mean (grey) value");
            return glm::vec3(count ? float(sum / count) : 0.0f);
        }
        if (tag == "blackbody") {
            warn(node, "blackbody spectra are not supported; using white (1, 1, 1)");
            return glm::vec3(1.0f);
        }
        fail(node, "expected a colour (<rgb>, <srgb>, <spectrum> or <float>)");
    }

    glm::mat4 parseTransform(pugi::xml_node node) {
        glm::mat4 m(1.0f);
        for (pugi::xml_node op : node.children()) {
            if (op.type() != pugi::node_element) continue;
            std::string tag = op.name();
            glm::mat4 t(1.0f);
            if (tag == "translate") {
                t = glm::translate(glm::mat4(1.0f), parseVec3(op, 0.0f));
            } else if (tag == "scale") {
                t = glm::scale(glm::mat4(1.0f), parseVec3(op, 1.0f));
            } else if (tag == "rotate") {
                glm::vec3 axis = parseVec3(op, 0.0f);
                if (glm::length(axis) == 0.0f)
                    fail(op, "rotation axis is zero (set x, y, z or value)");
                t = glm::rotate(glm::mat4(1.0f), glm::radians(parseNumber(op, "angle")),
                                glm::normalize(axis));
            } else if (tag == "matrix") {
                std::vector<float> v = parseNumbers(op, "value");
                if (v.size() == 16) {
                    for (int r = 0; r < 4; ++r)
                        for (int c = 0; c < 4; ++c)
                            t[c][r] = v[size_t(r * 4 + c)];  // row-major text
                } else if (v.size() == 9) {
                    for (int r = 0; r < 3; ++r)
                        for (int c = 0; c < 3; ++c) t[c][r] = v[size_t(r * 3 + c)];
                } else {
                    fail(op, fmt::format("expected 16 (4x4) or 9 (3x3) numbers, got {}", v.size()));
                }
            } else if (tag == "lookat") {
                auto vec = [&](const char* a, bool required) -> glm::vec3 {
                    if (!op.attribute(a)) {
                        if (required) fail(op, fmt::format("missing attribute '{}'", a));
                        return glm::vec3(0.0f);
                    }
                    std::vector<float> v = parseNumbers(op, a);
                    if (v.size() != 3)
                        fail(op, fmt::format("attribute '{}': expected 3 numbers", a));
                    return {v[0], v[1], v[2]};
                };
                glm::vec3 origin = vec("origin", true), target = vec("target", true);
                glm::vec3 up = vec("up", false);
                if (glm::length(target - origin) == 0.0f) fail(op, "origin and target coincide");
                t = lookAtMatrix(origin, target, up);
            } else {
                fail(op,
                     "unknown transform operation (expected translate, scale, rotate, matrix "
                     "or lookat)");
            }
            m = t * m;  // Mitsuba applies the operations in document order
        }
        return m;
    }

    // ---- references -------------------------------------------------------------------------
    pugi::xml_node resolveRef(pugi::xml_node ref) {
        std::string id = ref.attribute("id").value();
        if (id.empty()) fail(ref, "missing attribute 'id'");
        auto it = mIds.find(id);
        if (it == mIds.end()) {
            std::string known;
            int n = 0;
            for (auto& [k, v] : mIds) {
                if (n++ == 12) {
                    known += ", ...";
                    break;
                }
                known += (known.empty() ? "" : ", ") + k;
            }
            fail(ref, fmt::format("unknown id '{}' (defined ids: {})", id,
                                  known.empty() ? "none" : known));
        }
        return it->second;
    }
    pugi::xml_node deref(pugi::xml_node node) {
        int depth = 0;
        while (std::string(node.name()) == "ref") {
            node = resolveRef(node);
            if (++depth > 32) fail(node, "reference cycle");
        }
        return node;
    }

    // ---- textures ---------------------------------------------------------------------------
    // Texture index for a texture element (or -1 with `fallback` set when it cannot be used).
    int texture(pugi::xml_node node, bool raw, glm::vec3& fallback) {
        node = deref(node);
        auto key = std::make_pair(node.internal_object(), raw);
        if (auto it = mTextureCache.find(key); it != mTextureCache.end()) {
            fallback = it->second.second;
            return it->second.first;
        }
        Props p(*this, node);
        std::string type = node.attribute("type").value();
        int index = -1;
        fallback = glm::vec3(0.5f);
        glm::vec2 uvScale(1.0f);
        if (p.has("to_uv")) {
            glm::mat4 m = p.getTransform("to_uv");
            uvScale = {m[0][0], m[1][1]};
            if (m[1][0] != 0.0f || m[0][1] != 0.0f || m[3][0] != 0.0f || m[3][1] != 0.0f)
                warn(p.get("to_uv"),
                     "only the scale of to_uv is supported; rotation/translation ignored");
        }
        // Mitsuba 0.5 uv transform attributes.
        uvScale.x *= p.getFloat("uscale", 1.0f);
        uvScale.y *= p.getFloat("vscale", 1.0f);
        if (p.getFloat("uoffset", 0.0f) != 0.0f || p.getFloat("voffset", 0.0f) != 0.0f)
            warn(node, "uoffset/voffset are not supported; ignored");
        if (type == "bitmap") {
            std::string file = p.getString("filename", "");
            if (file.empty()) fail(node, "missing property 'filename'");
            if (p.has("raw")) raw = p.getBool("raw", raw);
            // Mitsuba 0.5: gamma = 1 means linear (raw) data, -1 or absent means sRGB.
            if (p.has("gamma")) raw = p.getFloat("gamma", -1.0f) == 1.0f;
            std::string path = resolve(file);
            index = detail::addBitmapTexture(mScene, path, raw, uvScale,
                                             fmt::format("{}: {}", where(node), describe(node)));
            if (index >= 0) fallback = detail::textureAverage(mScene.textures[size_t(index)]);
        } else if (type == "checkerboard") {
            Texture t;
            t.name = node.attribute("id") ? node.attribute("id").value() : "checkerboard";
            t.kind = TextureKind::Checkerboard;
            t.color0 = p.getColor("color0", glm::vec3(0.4f));
            t.color1 = p.getColor("color1", glm::vec3(0.2f));
            t.uvScale = uvScale;
            mScene.textures.push_back(t);
            index = int(mScene.textures.size() - 1);
            fallback = detail::textureAverage(t);
        } else {
            warn(node,
                 "texture type '" + type + "' is not supported; using a constant 0.5 instead");
            mTextureCache[key] = {index, fallback};
            return index;
        }
        p.reportUnused({"filter_type", "wrap_mode", "wrap_mode_u", "wrap_mode_v", "format",
                        "max_anisotropy", "cache", "accurate"});
        mTextureCache[key] = {index, fallback};
        return index;
    }

    // ---- materials --------------------------------------------------------------------------
    int defaultMaterial() {
        if (mDefaultMaterial < 0) {
            Material m;
            m.name = "default (diffuse 0.5)";
            mScene.materials.push_back(m);
            mDefaultMaterial = int(mScene.materials.size() - 1);
        }
        return mDefaultMaterial;
    }
    // The material a <bsdf> element describes (built once; wrappers copy their nested one).
    const Material& builtMaterial(pugi::xml_node node) {
        node = deref(node);
        if (std::string(node.name()) != "bsdf") fail(node, "expected a <bsdf>");
        const void* key = node.internal_object();
        auto it = mBuiltMaterials.find(key);
        if (it != mBuiltMaterials.end()) return it->second;
        for (auto& b : mBuilding)
            if (b == node) {
                std::string chain;
                for (auto& c : mBuilding) chain += describe(c) + " -> ";
                fail(node, "bsdf reference cycle: " + chain + describe(node));
            }
        mBuilding.push_back(node);
        Material m = buildMaterial(node);
        mBuilding.pop_back();
        return mBuiltMaterials.emplace(key, std::move(m)).first->second;
    }
    // Index into Scene::materials of a <bsdf> used by a shape (added on first use).
    int materialIndex(pugi::xml_node node) {
        const Material& m = builtMaterial(node);
        const void* key = deref(node).internal_object();
        if (auto it = mMaterialCache.find(key); it != mMaterialCache.end()) return it->second;
        mScene.materials.push_back(m);
        int index = int(mScene.materials.size() - 1);
        mMaterialCache[key] = index;
        return index;
    }
    // Nested <bsdf> children of a wrapper (twosided, normalmap, mask, ...).
    std::vector<pugi::xml_node> nestedBsdfs(Props& p) {
        std::vector<pugi::xml_node> r;
        for (pugi::xml_node o : p.objects()) {
            pugi::xml_node target = deref(o);
            if (std::string(target.name()) == "bsdf")
                r.push_back(o);
            else if (std::string(target.name()) != "texture")
                warn(o, "unexpected element inside a bsdf; ignored");
        }
        return r;
    }
    Material nestedMaterial(Props& p, const std::string& wrapper) {
        std::vector<pugi::xml_node> nested = nestedBsdfs(p);
        if (nested.empty()) fail(p.node(), wrapper + " needs a nested <bsdf>");
        if (nested.size() > 1)
            warn(p.node(),
                 fmt::format("{} nested bsdfs; Loom uses the first one only", nested.size()));
        return builtMaterial(nested[0]);
    }

    // Wrappers (twosided, normalmap, ...) copy their nested material; the wrapper's id names it.
    Material buildMaterial(pugi::xml_node node) {
        Material m = buildMaterialOf(node);
        m.origin = where(node);
        if (node.attribute("id")) m.name = node.attribute("id").value();
        return m;
    }
    Material buildMaterialOf(pugi::xml_node node) {
        Props p(*this, node);
        std::string type = node.attribute("type").value();
        Material m;
        m.name = node.attribute("id")
                     ? node.attribute("id").value()
                     : fmt::format("{}@{}", type, fileOf(node).line(node.offset_debug()));
        auto distribution = [&](const char* def) {
            std::string d = p.getString("distribution", def);
            if (d == "ggx") return Microfacet::GGX;
            if (d == "beckmann") return Microfacet::Beckmann;
            warn(p.get("distribution"),
                 "microfacet distribution '" + d + "' is not supported; using beckmann");
            return Microfacet::Beckmann;
        };
        auto roughness = [&]() {
            if (p.has("alpha_u") || p.has("alpha_v")) {
                float au = p.getFloat("alpha_u", 0.1f), av = p.getFloat("alpha_v", 0.1f);
                if (au != av)
                    warn(node, fmt::format("anisotropic roughness (alpha_u {}, alpha_v {}) is not "
                                           "supported; using the average {}",
                                           au, av, 0.5f * (au + av)));
                return 0.5f * (au + av);
            }
            pugi::xml_node a = p.get("alpha");
            if (a && std::string(a.name()) != "float")
                return p.getColor("alpha", glm::vec3(0.1f)).x;
            return p.getFloat("alpha", 0.1f);
        };
        auto dielectricEta = [&](float intDefault) {
            float intIor = p.getIor("int_ior", intDefault), extIor = p.getIor("ext_ior", 1.000277f);
            return intIor / extIor;
        };
        auto conductor = [&]() {
            bool hasEta = p.has("eta") || p.has("k");
            std::string material = p.getString("material", hasEta ? "" : "Cu");
            if (hasEta) {
                if (!material.empty())
                    warn(p.get("material"), "both material and eta/k given; using eta/k");
                m.conductorEta = p.getColor("eta", glm::vec3(0.0f));
                m.conductorK = p.getColor("k", glm::vec3(1.0f));
            } else if (!detail::conductorIor(material, m.conductorEta, m.conductorK)) {
                warn(p.get("material"), fmt::format("unknown conductor '{}' (known: {}); using a "
                                                    "perfect mirror",
                                                    material, detail::conductorNames()));
                m.conductorEta = glm::vec3(0.0f);
                m.conductorK = glm::vec3(1.0f);
            }
            // Mitsuba's eta/k are relative to the exterior IOR.
            float ext = p.getIor("ext_eta", 1.0f);
            m.conductorEta /= ext;
            m.conductorK /= ext;
            ColorTex spec = p.getColorTex("specular_reflectance", glm::vec3(1.0f));
            m.specularReflectance = spec.value;
            m.specularReflectanceTexture = spec.texture;
        };

        if (type == "diffuse") {
            ColorTex r = p.getColorTex("reflectance", glm::vec3(0.5f));
            m.reflectance = r.value;
            m.reflectanceTexture = r.texture;
        } else if (type == "roughdiffuse") {
            warn(node, "roughdiffuse (Oren-Nayar) approximated as Lambertian diffuse");
            ColorTex r = p.getColorTex("reflectance", glm::vec3(0.5f));
            m.reflectance = r.value;
            m.reflectanceTexture = r.texture;
            p.getColor("alpha", glm::vec3(0.2f));
        } else if (type == "twosided") {
            m = nestedMaterial(p, "twosided");
            m.twoSided = true;
        } else if (type == "dielectric" || type == "roughdielectric" || type == "thindielectric") {
            m.type = type == "roughdielectric" ? BsdfType::RoughDielectric : BsdfType::Dielectric;
            m.eta = dielectricEta(1.5046f);  // Mitsuba default int_ior = "bk7"
            m.specularReflectance = p.getColor("specular_reflectance", glm::vec3(1.0f));
            m.specularTransmittance = p.getColor("specular_transmittance", glm::vec3(1.0f));
            if (type == "roughdielectric") {
                m.distribution = distribution("beckmann");
                m.alpha = roughness();
            } else if (type == "thindielectric") {
                warn(node,
                     fmt::format("thindielectric approximated as a smooth dielectric with "
                                 "eta = 1 (light passes straight through; the sheet's ~{:.0f}% "
                                 "Fresnel reflection is dropped)",
                                 100.0f * 2.0f * std::pow((m.eta - 1) / (m.eta + 1), 2.0f)));
                m.eta = 1.0f;
            }
        } else if (type == "conductor" || type == "roughconductor") {
            m.type = type == "conductor" ? BsdfType::Conductor : BsdfType::RoughConductor;
            conductor();
            if (type == "roughconductor") {
                m.distribution = distribution("beckmann");
                m.alpha = roughness();
            }
        } else if (type == "plastic" || type == "roughplastic") {
            m.type = type == "plastic" ? BsdfType::Plastic : BsdfType::RoughPlastic;
            ColorTex r = p.getColorTex("diffuse_reflectance", glm::vec3(0.5f));
            m.reflectance = r.value;
            m.reflectanceTexture = r.texture;
            m.specularReflectance = p.getColor("specular_reflectance", glm::vec3(1.0f));
            m.eta = dielectricEta(1.49f);  // Mitsuba default int_ior = "polypropylene"
            m.nonlinear = p.getBool("nonlinear", false);
            if (type == "roughplastic") {
                m.distribution = distribution("beckmann");
                m.alpha = roughness();
            }
        } else if (type == "normalmap") {
            m = nestedMaterial(p, "normalmap");
            // SMS variant (Zeltner et al. 2020): filename + tiles + use_slopes. Mitsuba 3 uses a
            // nested texture named "normalmap" instead.
            glm::vec3 unused;
            int tex = -1;
            float tiles = p.getFloat("tiles", 1.0f);
            if (p.has("filename")) {
                std::string path = resolve(p.getString("filename", ""));
                tex = detail::addBitmapTexture(mScene, path, true, glm::vec2(tiles),
                                               fmt::format("{}: {}", where(node), describe(node)),
                                               "the nested bsdf is used without a normal map");
            } else if (p.has("normalmap")) {
                tex = texture(p.get("normalmap"), true, unused);
                if (tex < 0)
                    warn(node, "normal map unavailable; the nested bsdf is used without it");
            } else {
                fail(node, "missing property 'filename' (SMS normalmap) or texture 'normalmap'");
            }
            // Mitsuba 3's normalmap interpolates the normals themselves.
            m.normalMapUseSlopes = p.has("filename") && p.getBool("use_slopes", true);
            if (tex >= 0) {
                m.normalMap = tex;
                m.name += "+normalmap";
            }
            p.reportUnused({"lean_fallback", "lean_fallback_alpha", "lean_fallback_material"});
            return m;
        } else if (type == "bumpmap") {
            warn(node, "bumpmap is not supported; the nested bsdf is used without bump mapping");
            for (pugi::xml_node o : p.objects())
                if (std::string(deref(o).name()) == "bsdf") return builtMaterial(o);
            fail(node, "bumpmap needs a nested <bsdf>");
        } else if (type == "mask") {
            warn(node, "mask (opacity) is not supported; the nested bsdf is fully opaque");
            p.get("opacity");
            m = nestedMaterial(p, "mask");
        } else if (type == "null") {
            m.type = BsdfType::Null;
        } else if (type == "coating" || type == "roughcoating" || type == "blendbsdf" ||
                   type == "mixturebsdf") {
            warn(node, type + " is not supported; using its first nested bsdf");
            for (pugi::xml_node o : p.objects())
                if (std::string(deref(o).name()) == "bsdf") {
                    m = builtMaterial(o);
                    p.reportUnused({"weight", "weights", "int_ior", "ext_ior", "thickness",
                                    "sigma_a", "alpha", "distribution", "specular_reflectance"});
                    return m;
                }
            fail(node, type + " needs a nested <bsdf>");
        } else if (type == "phong") {
            float exponent = p.getFloat("exponent", 30.0f);
            m.type = BsdfType::RoughPlastic;
            m.distribution = Microfacet::Beckmann;
            // Beckmann alpha with the same lobe width as Phong (Walter et al. 2007, Eq. 30).
            m.alpha = std::sqrt(2.0f / (exponent + 2.0f));
            ColorTex r = p.getColorTex("diffuse_reflectance", glm::vec3(0.5f));
            m.reflectance = r.value;
            m.reflectanceTexture = r.texture;
            m.specularReflectance = p.getColor("specular_reflectance", glm::vec3(0.2f));
            warn(node, fmt::format("phong approximated as roughplastic (beckmann alpha {:.3f})",
                                   m.alpha));
        } else if (type == "principled") {
            // Closest Loom lobe: metal -> rough conductor tinted by base_color, transmissive ->
            // rough dielectric, otherwise a rough plastic with the base colour underneath.
            ColorTex base = p.getColorTex("base_color", glm::vec3(0.5f));
            float metallic = p.getColor("metallic", glm::vec3(0.0f)).x;
            float specTrans = p.getColor("spec_trans", glm::vec3(0.0f)).x;
            float rough = p.getColor("roughness", glm::vec3(0.5f)).x;
            m.alpha = std::max(rough * rough, 1e-3f);
            m.distribution = Microfacet::GGX;
            m.eta = p.getFloat("eta", 1.5f);
            if (metallic >= 0.5f) {
                m.type = BsdfType::RoughConductor;
                m.conductorEta = glm::vec3(0.0f);
                m.conductorK = glm::vec3(1.0f);
                m.specularReflectance = base.value;
                m.specularReflectanceTexture = base.texture;
            } else if (specTrans >= 0.5f) {
                m.type = BsdfType::RoughDielectric;
                m.specularTransmittance = base.value;
            } else {
                m.type = BsdfType::RoughPlastic;
                m.reflectance = base.value;
                m.reflectanceTexture = base.texture;
            }
            warn(node,
                 fmt::format("principled approximated as {} (metallic {:.3g} and spec_trans "
                             "{:.3g} snapped to 0 or 1, alpha = roughness^2 = {:.3f}); sheen, "
                             "clearcoat, anisotropy and specular tint are dropped",
                             m.type == BsdfType::RoughConductor    ? "roughconductor"
                             : m.type == BsdfType::RoughDielectric ? "roughdielectric"
                                                                   : "roughplastic",
                             metallic, specTrans, m.alpha));
            p.reportUnused({"specular", "spec_tint", "sheen", "sheen_tint", "clearcoat",
                            "clearcoat_gloss", "anisotropic", "flatness", "diff_trans"});
            return m;
        } else {
            // One warning for the whole element, not one per property.
            warn(node, "bsdf type '" + type + "' is not supported; using diffuse 0.5 instead");
            return m;
        }
        p.reportUnused({});
        return m;
    }

    // ---- shapes -----------------------------------------------------------------------------
    int meshIndex(const std::string& key, const std::function<Mesh()>& make) {
        if (auto it = mMeshCache.find(key); it != mMeshCache.end()) return it->second;
        mScene.meshes.push_back(make());
        int index = int(mScene.meshes.size() - 1);
        mMeshCache[key] = index;
        return index;
    }

    void processShape(pugi::xml_node node) {
        Props p(*this, node);
        std::string type = node.attribute("type").value();
        Shape shape;
        shape.toWorld = p.has("to_world") ? p.getTransform("to_world") : glm::mat4(1.0f);
        bool faceNormals = p.getBool("face_normals", false);
        bool flip = p.getBool("flip_normals", false);
        auto finishMesh = [&](Mesh m, bool fileHadNormals) {
            // Mitsuba recomputes smooth vertex normals for meshes without them.
            if (faceNormals) {
                m.normals.clear();
                m.faceNormals = true;
            } else if (!fileHadNormals) {
                computeVertexNormals(m);
            }
            if (flip) flipNormals(m);
            return m;
        };
        std::string variant = fmt::format("|fn{}|flip{}", faceNormals, flip);
        if (type == "obj" || type == "ply") {
            std::string file = p.getString("filename", "");
            if (file.empty()) fail(node, "missing property 'filename'");
            std::string path = resolve(file);
            if (!fs::exists(path))
                fail(p.get("filename"),
                     fmt::format("mesh file not found: '{}' (tried '{}')", file, path));
            bool flipTex = p.getBool("flip_tex_coords", true);
            shape.name = fs::path(file).stem().string();
            shape.mesh = meshIndex(path + variant + (flipTex ? "|ft" : ""), [&] {
                Mesh m = type == "obj" ? readObjMesh(path, flipTex) : readPly(path);
                bool had = !m.normals.empty();
                m.name = file;
                return finishMesh(std::move(m), had);
            });
        } else if (type == "rectangle" || type == "cube" || type == "disk") {
            shape.name = type;
            shape.mesh = meshIndex(type + variant, [&] {
                return finishMesh(type == "rectangle" ? makeRectangle()
                                  : type == "cube"    ? makeCube()
                                                      : makeDisk(),
                                  true);
            });
        } else if (type == "sphere") {
            shape.name = type;
            glm::vec3 center = p.getVector("center", glm::vec3(0.0f));
            float radius = p.getFloat("radius", 1.0f);
            shape.toWorld = shape.toWorld * glm::translate(glm::mat4(1.0f), center) *
                            glm::scale(glm::mat4(1.0f), glm::vec3(radius));
            shape.mesh = meshIndex(type + variant, [&] { return finishMesh(makeSphere(), true); });
        } else if (type == "cylinder") {
            shape.name = type;
            glm::vec3 p0 = p.getVector("p0", glm::vec3(0.0f)),
                      p1 = p.getVector("p1", glm::vec3(0, 0, 1));
            float radius = p.getFloat("radius", 1.0f);
            if (glm::length(p1 - p0) == 0.0f) fail(node, "p0 and p1 coincide");
            shape.toWorld = shape.toWorld * cylinderTransform(p0, p1, radius);
            shape.mesh =
                meshIndex(type + variant, [&] { return finishMesh(makeCylinder(), true); });
        } else if (type == "serialized") {
            warn(node,
                 "the Mitsuba 'serialized' mesh format is not supported; shape skipped "
                 "(convert it to .ply or .obj)");
            return;
        } else {
            warn(node, "shape type '" + type + "' is not supported; shape skipped");
            return;
        }
        if (node.attribute("id")) shape.name = node.attribute("id").value();

        // Nested objects: one bsdf, an area emitter, media (ignored).
        for (pugi::xml_node o : p.objects()) {
            pugi::xml_node target = deref(o);
            std::string tag = target.name();
            if (tag == "bsdf") {
                if (shape.material >= 0)
                    warn(o, "more than one bsdf; using the first");
                else
                    shape.material = materialIndex(o);
            } else if (tag == "emitter") {
                areaEmitter(target, shape);
            } else if (tag == "medium") {
                warn(o, "participating media are not supported; the shape's medium is ignored");
            } else {
                warn(o, "unexpected <" + tag + "> inside a shape; ignored");
            }
        }
        if (p.has("interior") || p.has("exterior")) {
            pugi::xml_node m = p.has("interior") ? p.get("interior") : p.get("exterior");
            p.get("exterior");
            warn(m, "participating media are not supported; the shape's medium is ignored");
        }
        if (shape.material < 0) shape.material = defaultMaterial();

        // SMS tags (Zeltner et al. 2020 scenes): caster type follows the BSDF.
        bool casterSingle = p.getBool("caustic_caster_single", false);
        bool casterMulti = p.getBool("caustic_caster_multi", false);
        if (casterSingle || casterMulti) {
            BsdfType t = mScene.materials[size_t(shape.material)].type;
            if (t == BsdfType::Dielectric || t == BsdfType::RoughDielectric)
                shape.flags |= kCausticCasterRefract;
            else if (t == BsdfType::Conductor || t == BsdfType::RoughConductor)
                shape.flags |= kCausticCasterReflect;
            else
                warn(node, "caustic caster tag on a non-specular bsdf; tag ignored");
            if (casterMulti) shape.flags |= kCausticMulti;
        }
        if (p.getBool("caustic_receiver", false)) shape.flags |= kCausticReceiver;
        if (p.getBool("caustic_bouncer", false)) shape.flags |= kCausticBouncer;
        p.reportUnused({});
        shape.origin = where(node);
        mScene.shapes.push_back(shape);
    }

    uint32_t causticEmitterFlags(Props& p) {
        bool single = p.getBool("caustic_emitter_single", false);
        bool multi = p.getBool("caustic_emitter_multi", false);
        return (single || multi ? kCausticEmitter : 0u) | (multi ? kCausticMulti : 0u);
    }

    void areaEmitter(pugi::xml_node node, Shape& shape) {
        Props p(*this, node);
        std::string type = node.attribute("type").value();
        if (type != "area") {
            warn(node, "only area emitters can be attached to shapes; emitter ignored");
            return;
        }
        shape.emission = p.getColor("radiance", glm::vec3(1.0f));
        shape.flags |= causticEmitterFlags(p);
        p.reportUnused({"sampling_weight"});
    }

    // ---- emitters ---------------------------------------------------------------------------
    void processEmitter(pugi::xml_node node) {
        Props p(*this, node);
        std::string type = node.attribute("type").value();
        Light light;
        glm::mat4 toWorld = p.has("to_world") ? p.getTransform("to_world") : glm::mat4(1.0f);
        light.flags = causticEmitterFlags(p);
        if (type == "point") {
            light.type = LightType::Point;
            light.intensity = p.getColor("intensity", glm::vec3(1.0f));
            light.position = p.has("position") ? p.getVector("position", glm::vec3(0.0f))
                                               : glm::vec3(toWorld[3]);
            light.toWorld = toWorld;
        } else if (type == "spot") {
            light.type = LightType::Spot;
            light.intensity = p.getColor("intensity", glm::vec3(1.0f));
            light.cutoffAngle = p.getFloat("cutoff_angle", 20.0f);
            light.beamWidth = p.getFloat("beam_width", light.cutoffAngle * 0.75f);
            light.toWorld = toWorld;
            light.position = glm::vec3(toWorld[3]);
            light.direction = glm::normalize(glm::vec3(toWorld * glm::vec4(0, 0, 1, 0)));
            if (p.has("texture")) {
                p.get("texture");
                warn(node, "projected spot textures are not supported; ignored");
            }
        } else if (type == "directional") {
            light.type = LightType::Directional;
            light.intensity = p.getColor("irradiance", glm::vec3(1.0f));
            glm::vec3 dir = p.has("direction") ? p.getVector("direction", glm::vec3(0, 0, 1))
                                               : glm::vec3(toWorld * glm::vec4(0, 0, 1, 0));
            if (glm::length(dir) == 0.0f) fail(node, "direction is zero");
            light.direction = glm::normalize(dir);  // direction of propagation (Mitsuba)
            light.toWorld = toWorld;
        } else if (type == "envmap") {
            light.type = LightType::Environment;
            std::string file = p.getString("filename", "");
            if (file.empty()) fail(node, "missing property 'filename'");
            light.scale = p.getFloat("scale", 1.0f);
            light.toWorld = toWorld;
            light.envTexture =
                detail::addBitmapTexture(mScene, resolve(file), false, glm::vec2(1.0f),
                                         fmt::format("{}: {}", where(node), describe(node)));
            if (light.envTexture < 0) {
                light.type = LightType::Constant;
                light.intensity = glm::vec3(0.5f);
                warn(node, "environment map missing; using a constant environment of 0.5 * scale");
            }
        } else if (type == "constant") {
            light.type = LightType::Constant;
            light.intensity = p.getColor("radiance", glm::vec3(1.0f));
        } else if (type == "area") {
            warn(node, "an area emitter must be nested in a shape; ignored");
            return;
        } else {
            warn(node, "emitter type '" + type + "' is not supported; emitter skipped");
            return;
        }
        p.reportUnused({"sampling_weight", "gamma", "cache"});
        light.origin = where(node);
        mScene.lights.push_back(light);
    }

    // ---- sensor -----------------------------------------------------------------------------
    void processSensor(pugi::xml_node node) {
        if (mHaveCamera) {
            warn(node, "more than one sensor; Loom uses the first");
            return;
        }
        Props p(*this, node);
        std::string type = node.attribute("type").value();
        Camera& cam = mScene.camera;
        cam = Camera{};
        if (type == "thinlens") {
            cam.type = CameraType::ThinLens;
            if (!p.has("aperture_radius")) fail(node, "missing property 'aperture_radius'");
            if (!p.has("focus_distance")) fail(node, "missing property 'focus_distance'");
            cam.apertureRadius = p.getFloat("aperture_radius", 0.0f);
            cam.focusDistance = p.getFloat("focus_distance", 1.0f);
        } else if (type != "perspective") {
            warn(node, "sensor type '" + type +
                           "' is not supported; approximated as a perspective camera");
        }
        // Film first: the fov conversions below need its aspect ratio.
        for (pugi::xml_node o : p.objects()) {
            pugi::xml_node target = deref(o);
            std::string tag = target.name();
            if (tag == "film") {
                Props f(*this, target);
                int w = f.getInt("width", 768), h = f.getInt("height", 576);
                if (w < 1 || h < 1 || w > 16384 || h > 16384)
                    fail(target, fmt::format("film size {}x{} is outside 1..16384", w, h));
                cam.filmWidth = uint32_t(w);
                cam.filmHeight = uint32_t(h);
                f.reportUnused(
                    {"crop_offset_x", "crop_offset_y",  "crop_width",         "crop_height",
                     "file_format",   "pixel_format",   "component_format",   "rfilter",
                     "gamma",         "banner",         "high_quality_edges", "sample_border",
                     "compensate",    "tonemap_method", "exposure",           "key",
                     "burn",          "attach_log",     "write_log",          "dither",
                     "label",         "sample_count"});
            } else if (tag == "sampler") {
                debug(target, "samplers are chosen by the render graph; ignored");
            } else {
                warn(o, "unexpected <" + tag + "> inside a sensor; ignored");
            }
        }
        cam.toWorld = p.has("to_world") ? p.getTransform("to_world") : glm::mat4(1.0f);
        float aspect = cam.filmWidth && cam.filmHeight
                           ? float(cam.filmWidth) / float(cam.filmHeight)
                           : 768.0f / 576.0f;
        std::string axis = p.getString("fov_axis", "x");
        float fov = 0.0f;
        if (p.has("fov")) {
            fov = p.getFloat("fov", 45.0f);
        } else {
            // focal_length is the 35 mm equivalent; Mitsuba measures it along the diagonal.
            std::string f = p.getString("focal_length", "50mm");
            float mm = std::strtof(f.c_str(), nullptr);
            if (mm <= 0.0f) fail(p.get("focal_length"), "expected a focal length like '50mm'");
            fov = glm::degrees(2.0f *
                               std::atan(std::sqrt(36.0f * 36.0f + 24.0f * 24.0f) / (2.0f * mm)));
            axis = "diagonal";
        }
        if (axis == "x")
            cam.fovAxis = Camera::FovAxis::X;
        else if (axis == "y")
            cam.fovAxis = Camera::FovAxis::Y;
        else if (axis == "smaller")
            cam.fovAxis = Camera::FovAxis::Smaller;
        else if (axis == "larger")
            cam.fovAxis = Camera::FovAxis::Larger;
        else if (axis == "diagonal") {
            // Convert to the x axis: tan(fx/2) = tan(fd/2) * w / sqrt(w^2 + h^2).
            float t =
                std::tan(glm::radians(fov) * 0.5f) * aspect / std::sqrt(aspect * aspect + 1.0f);
            fov = glm::degrees(2.0f * std::atan(t));
            cam.fovAxis = Camera::FovAxis::X;
        } else {
            fail(p.get("fov_axis"),
                 "expected x, y, smaller, larger or diagonal, got '" + axis + "'");
        }
        if (!(fov > 0.0f && fov < 180.0f))
            fail(node, fmt::format("fov must be in (0, 180), got {}", fov));
        cam.fov = fov;
        if (p.has("principal_point_offset_x") || p.has("principal_point_offset_y")) {
            p.get("principal_point_offset_x");
            p.get("principal_point_offset_y");
            warn(node, "principal point offsets are not supported; ignored");
        }
        p.reportUnused({"near_clip", "far_clip", "shutter_open", "shutter_close",
                        "shutter_open_time", "srf", "sample_count"});
        mHaveCamera = true;
    }

    // ---- scene ------------------------------------------------------------------------------
    void processChildren(pugi::xml_node root) {
        for (pugi::xml_node child : root.children()) {
            if (child.type() != pugi::node_element) continue;
            std::string tag = child.name();
            if (tag == "default") continue;  // handled while parsing
            if (tag == "shape")
                processShape(child);
            else if (tag == "emitter")
                processEmitter(child);
            else if (tag == "sensor")
                processSensor(child);
            else if (tag == "integrator" || tag == "sampler" || tag == "film" || tag == "rfilter") {
                // Referenced films/samplers (<ref id> in the sensor) are read there.
                if (!child.attribute("id"))
                    debug(child, "chosen by the render graph in Loom; ignored");
            } else if (tag == "bsdf" || tag == "texture" || tag == "spectrum" || tag == "rgb") {
                // Built when referenced.
            } else if (tag == "medium" || tag == "phase" || tag == "volume")
                warn(child, "participating media are not supported; ignored");
            else if (tag == "include") {
                std::string file = child.attribute("filename").value();
                if (file.empty()) fail(child, "missing attribute 'filename'");
                std::string path = resolve(file);
                if (!fs::exists(path))
                    fail(child,
                         fmt::format("included file not found: '{}' (tried '{}')", file, path));
                std::string canonical = fs::weakly_canonical(path).string();
                std::string chain;
                for (auto& f : mIncludeStack) chain += f + " -> ";
                if (std::find(mIncludeStack.begin(), mIncludeStack.end(), canonical) !=
                    mIncludeStack.end())
                    fail(child, "include cycle: " + chain + canonical);
                if (mIncludeStack.size() >= 32) fail(child, "includes nested deeper than 32 files");
                XmlFile& inc = parseFile(path);
                mIncludeStack.push_back(canonical);
                processChildren(inc.doc.document_element());
                mIncludeStack.pop_back();
            } else if (tag == "alias") {
                mIds[child.attribute("as").value()] = resolveRef(child);
            } else if (tag == "path") {
                mSearchPaths.push_back(
                    detail::resolvePath(fileOf(child).dir, child.attribute("value").value()));
            } else {
                warn(child, "unknown element; ignored");
            }
        }
    }

    std::string resolve(const std::string& file) {
        std::string first;
        for (auto it = mSearchPaths.rbegin(); it != mSearchPaths.rend(); ++it) {
            std::string p = detail::resolvePath(*it, file);
            if (first.empty()) first = p;
            if (fs::exists(p)) return p;
        }
        return first;
    }

private:
    friend class Props;
    Scene& mScene;
    std::vector<std::unique_ptr<XmlFile>> mFiles;
    std::vector<std::string> mSearchPaths;
    std::map<std::string, std::string> mDefaults;
    std::map<std::string, pugi::xml_node> mIds;
    std::vector<std::string> mIncludeStack;  // the files being processed, outermost first
    std::map<const void*, Material> mBuiltMaterials;
    std::vector<pugi::xml_node> mBuilding;  // wrappers being built, to name reference cycles
    std::map<const void*, int> mMaterialCache;
    std::map<std::pair<const void*, bool>, std::pair<int, glm::vec3>> mTextureCache;
    std::map<std::string, int> mMeshCache;
    int mDefaultMaterial = -1;
    bool mHaveCamera = false;

    XmlFile& parseFile(const std::string& path) {
        auto file = std::make_unique<XmlFile>();
        file->path = path;
        file->dir = fs::path(path).parent_path().string();
        std::ifstream in(path, std::ios::binary);
        if (!in) throw UserError(path + ": cannot open file");
        std::stringstream ss;
        ss << in.rdbuf();
        file->text = ss.str();
        file->lineStarts.push_back(0);
        for (size_t i = 0; i < file->text.size(); ++i)
            if (file->text[i] == '\n') file->lineStarts.push_back(i + 1);
        pugi::xml_parse_result result = file->doc.load_buffer(
            file->text.data(), file->text.size(), pugi::parse_default, pugi::encoding_utf8);
        if (!result)
            throw UserError(fmt::format("{}:{}:{}: XML syntax error: {}", path,
                                        file->line(result.offset), file->column(result.offset),
                                        result.description()));
        checkDepth(*file);
        mSearchPaths.push_back(file->dir);
        mFiles.push_back(std::move(file));
        XmlFile& f = *mFiles.back();
        pugi::xml_node root = f.doc.document_element();
        std::string version = root.attribute("version").value();
        if (version.empty()) {
            logDebug("{}: <scene> has no version attribute; assuming 3.0.0", path);
        } else {
            f.majorVersion = std::atoi(version.c_str());
        }
        if (f.majorVersion < 2) normaliseNames(root);
        for (pugi::xml_node d : root.children("default")) {
            std::string name = d.attribute("name").value();
            if (name.empty() || !d.attribute("value"))
                fail(d, "expected attributes 'name' and 'value'");
            mDefaults.emplace(name, d.attribute("value").value());  // the first definition wins
        }
        substitute(root);
        collectIds(root);
        return f;
    }

    // The loader recurses over elements (substitution, wrappers), so nesting is bounded before
    // any of it runs; pugixml's own parse and traversal do not recurse.
    static constexpr int kMaxXmlDepth = 128;
    static void checkDepth(const XmlFile& file) {
        struct Walker : pugi::xml_tree_walker {
            pugi::xml_node tooDeep;
            bool for_each(pugi::xml_node& n) override {
                if (depth() < kMaxXmlDepth) return true;
                tooDeep = n;
                return false;
            }
        } walker;
        const_cast<pugi::xml_document&>(file.doc).traverse(walker);
        if (walker.tooDeep)
            throw UserError(fmt::format("{}:{}: <{}>: XML elements nested deeper than {} levels",
                                        file.path, file.line(walker.tooDeep.offset_debug()),
                                        walker.tooDeep.name(), kMaxXmlDepth));
    }

    // Mitsuba 0.5/0.6 spell names in camelCase; everything else in the loader uses 2/3 names.
    void normaliseNames(pugi::xml_node node) {
        for (pugi::xml_node n : node.children()) {
            if (n.type() != pugi::node_element) continue;
            n.set_name(toLower(n.name()).c_str());
            if (pugi::xml_attribute a = n.attribute("name");
                a && std::string(n.name()) != "default")
                a.set_value(camelToSnake(a.value()).c_str());
            normaliseNames(n);
        }
    }

    // Replaces $name in every attribute value with the <default> value.
    void substitute(pugi::xml_node node) {
        for (pugi::xml_node n : node.children()) {
            if (n.type() != pugi::node_element) continue;
            if (std::string(n.name()) == "default") continue;
            for (pugi::xml_attribute a : n.attributes()) {
                std::string v = a.value();
                if (v.find('$') == std::string::npos) continue;
                std::string out;
                for (size_t i = 0; i < v.size(); ++i) {
                    if (v[i] != '$') {
                        out += v[i];
                        continue;
                    }
                    size_t j = i + 1;
                    while (j < v.size() &&
                           (std::isalnum(static_cast<unsigned char>(v[j])) || v[j] == '_'))
                        ++j;
                    std::string name = v.substr(i + 1, j - i - 1);
                    auto it = mDefaults.find(name);
                    if (name.empty() || it == mDefaults.end())
                        fail(n,
                             fmt::format("attribute '{}': undefined variable '${}' (add <default "
                                         "name=\"{}\" value=\"...\"/> or pass it as a define, like "
                                         "mitsuba -D{}=...)",
                                         a.name(), name, name, name));
                    out += it->second;
                    i = j - 1;
                }
                a.set_value(out.c_str());
            }
            substitute(n);
        }
    }

    void collectIds(pugi::xml_node node) {
        for (pugi::xml_node n : node.children()) {
            if (n.type() != pugi::node_element) continue;
            std::string tag = n.name();
            if (tag != "ref" && tag != "alias" && n.attribute("id")) {
                std::string id = n.attribute("id").value();
                auto [it, inserted] = mIds.emplace(id, n);
                if (!inserted)
                    fail(n, fmt::format("duplicate id '{}' (first defined at {})", id,
                                        where(it->second)));
            }
            collectIds(n);
        }
    }
};

// ---- Props ----------------------------------------------------------------------------------

Props::Props(MitsubaLoader& loader, pugi::xml_node plugin) : mLoader(loader), mNode(plugin) {
    for (pugi::xml_node c : plugin.children()) {
        if (c.type() != pugi::node_element) continue;
        std::string tag = c.name();
        std::string name = c.attribute("name").value();
        if (!name.empty() && (isPropertyTag(tag) || isObjectTag(tag))) {
            if (mNamed.count(name))
                loader.fail(
                    c, fmt::format("property '{}' is specified more than once (first at {})", name,
                                   loader.where(mNamed[name])));
            mNamed[name] = c;
        } else if (isObjectTag(tag)) {
            mObjects.push_back(c);
        } else if (isPropertyTag(tag)) {
            loader.fail(c, "missing attribute 'name'");
        } else if (tag == "lookat" || tag == "translate" || tag == "rotate" || tag == "scale" ||
                   tag == "matrix") {
            loader.fail(c, "transform operations must be inside a <transform> element");
        } else {
            loader.warn(c, "unknown element; ignored");
        }
    }
}

pugi::xml_node Props::get(const std::string& name) {
    auto it = mNamed.find(name);
    if (it == mNamed.end()) return {};
    mUsed.insert(name);
    return it->second;
}

float Props::getFloat(const std::string& name, float def) {
    pugi::xml_node n = get(name);
    if (!n) return def;
    std::string tag = n.name();
    if (tag != "float" && tag != "integer") mLoader.fail(n, "expected a <float>");
    return mLoader.parseNumber(n, "value");
}

int Props::getInt(const std::string& name, int def) {
    pugi::xml_node n = get(name);
    if (!n) return def;
    if (std::string(n.name()) != "integer") mLoader.fail(n, "expected an <integer>");
    float v = mLoader.parseNumber(n, "value");
    if (v != std::floor(v)) mLoader.fail(n, "expected an integer value");
    // 2^31 is exact in float; anything at or beyond it (inf included) does not fit an int.
    if (!(v >= -2147483648.0f && v < 2147483648.0f))
        mLoader.fail(n, "integer value out of range (32-bit)");
    return int(v);
}

bool Props::getBool(const std::string& name, bool def) {
    pugi::xml_node n = get(name);
    if (!n) return def;
    if (std::string(n.name()) != "boolean") mLoader.fail(n, "expected a <boolean>");
    std::string v = toLower(n.attribute("value").value());
    if (v == "true" || v == "1") return true;
    if (v == "false" || v == "0") return false;
    mLoader.fail(n, "attribute 'value': expected true or false, got '" + v + "'");
}

std::string Props::getString(const std::string& name, const std::string& def) {
    pugi::xml_node n = get(name);
    if (!n) return def;
    if (std::string(n.name()) != "string") mLoader.fail(n, "expected a <string>");
    return n.attribute("value").value();
}

glm::vec3 Props::getVector(const std::string& name, const glm::vec3& def) {
    pugi::xml_node n = get(name);
    if (!n) return def;
    std::string tag = n.name();
    if (tag != "point" && tag != "vector") mLoader.fail(n, "expected a <point> or <vector>");
    return mLoader.parseVec3(n, 0.0f);
}

glm::mat4 Props::getTransform(const std::string& name) {
    pugi::xml_node n = get(name);
    if (!n) return glm::mat4(1.0f);
    if (std::string(n.name()) != "transform") mLoader.fail(n, "expected a <transform>");
    return mLoader.parseTransform(n);
}

ColorTex Props::getColorTex(const std::string& name, const glm::vec3& def, bool raw) {
    pugi::xml_node n = get(name);
    if (!n) return {def, -1};
    pugi::xml_node target = n;
    if (std::string(n.name()) == "ref") target = mLoader.deref(n);
    std::string tag = target.name();
    // Mitsuba 2 also writes textures as <spectrum name="..." type="bitmap">.
    if (tag == "texture" || ((tag == "spectrum" || tag == "rgb") && target.attribute("type"))) {
        ColorTex r;
        r.texture = mLoader.texture(target, raw, r.value);
        return r;
    }
    return {mLoader.parseColorElement(target), -1};
}

glm::vec3 Props::getColor(const std::string& name, const glm::vec3& def) {
    ColorTex c = getColorTex(name, def);
    if (c.texture >= 0)
        mLoader.warn(get(name), fmt::format("property '{}' cannot be textured in Loom; using the "
                                            "texture's mean ({:.3g}, {:.3g}, {:.3g})",
                                            name, c.value.x, c.value.y, c.value.z));
    return c.value;
}

float Props::getIor(const std::string& name, float def) {
    pugi::xml_node n = get(name);
    if (!n) return def;
    if (std::string(n.name()) == "string") {
        float ior = 1.0f;
        std::string v = n.attribute("value").value();
        if (!detail::namedIor(v, ior))
            mLoader.fail(n, "unknown IOR name '" + v + "' (e.g. vacuum, air, water, bk7, diamond)");
        return ior;
    }
    return getFloat(name, def);
}

void Props::reportUnused(std::initializer_list<const char*> quiet) {
    for (auto& [name, node] : mNamed) {
        if (mUsed.count(name)) continue;
        const std::string& key = name;  // clang 14 cannot capture a structured binding
        bool isQuiet = std::find_if(quiet.begin(), quiet.end(),
                                    [&](const char* q) { return key == q; }) != quiet.end();
        if (isQuiet)
            mLoader.debug(node, "not used by Loom");
        else
            mLoader.warn(node, "property '" + name + "' is not supported by Loom; ignored");
    }
}

}  // namespace

Scene loadMitsubaScene(const std::string& path, const std::map<std::string, std::string>& defines) {
    Scene scene;
    scene.sourceFile = path;
    MitsubaLoader loader(scene, defines);
    loader.load(path);
    return scene;
}

}  // namespace loom::scene
