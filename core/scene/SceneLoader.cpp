#include "core/scene/SceneLoader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>

#include <fmt/format.h>

#include "core/image/Image.h"
#include "core/scene/Camera.h"
#include "core/scene/Shapes.h"
#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom::scene {

namespace fs = std::filesystem;

namespace {

std::string lowerExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

float srgbToLinear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

// sRGB decode with a table for 8-bit values (megapixel textures would otherwise spend seconds
// in pow()).
float srgbToLinearFast(float v) {
    static const std::array<float, 256> kTable = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[size_t(i)] = srgbToLinear(float(i) / 255.0f);
        return t;
    }();
    float scaled = v * 255.0f;
    long i = std::lround(scaled);
    if (i >= 0 && i < 256 && std::fabs(scaled - float(i)) < 1e-3f) return kTable[size_t(i)];
    return srgbToLinear(v);
}

// A single PLY file as a scene: one grey diffuse shape and the default camera/light.
Scene loadPlyScene(const std::string& path) {
    Scene scene;
    scene.meshes.push_back(readPly(path));
    scene.materials.push_back(Material{});
    scene.materials.back().name = "default";
    Shape shape;
    shape.name = fs::path(path).stem().string();
    shape.mesh = 0;
    shape.material = 0;
    scene.shapes.push_back(shape);
    Light env;
    env.type = LightType::Constant;
    scene.lights.push_back(env);
    detail::addWarning(scene, path +
                                  ": a PLY file has no lights or camera; added a constant "
                                  "environment light of radiance 1 and a default camera");
    detail::setDefaultCamera(scene);
    return scene;
}

}  // namespace

Scene loadScene(const std::string& path, const SceneLoadOptions& options) {
    if (!fs::exists(path)) throw UserError(path + ": scene file not found");
    std::string ext = lowerExtension(path);
    Scene scene;
    if (ext == ".json")
        scene = loadJsonScene(path);
    else if (ext == ".xml")
        scene = loadMitsubaScene(path, options.defines);
    else if (ext == ".gltf" || ext == ".glb")
        scene = loadGltfScene(path);
    else if (ext == ".obj")
        scene = loadObjScene(path);
    else if (ext == ".ply")
        scene = loadPlyScene(path);
    else
        throw UserError(path + ": unknown scene format '" + ext +
                        "' (expected .json, .xml, .gltf, .glb, .obj or .ply)");
    scene.sourceFile = fs::absolute(path).lexically_normal().string();
    detail::validateScene(scene);
    return scene;
}

namespace detail {

void addWarning(Scene& scene, const std::string& message) {
    logWarning("{}", message);
    scene.warnings.push_back(message);
}

std::string resolvePath(const std::string& baseDir, const std::string& file) {
    fs::path p(file);
    if (p.is_relative() && !baseDir.empty()) p = fs::path(baseDir) / p;
    return p.lexically_normal().string();
}

int addBitmapTexture(Scene& scene, const std::string& path, bool raw, glm::vec2 uvScale,
                     const std::string& context, const std::string& fallback) {
    for (size_t i = 0; i < scene.textures.size(); ++i) {
        const Texture& t = scene.textures[i];
        if (t.kind == TextureKind::Bitmap && t.path == path && t.isNormalMap == raw &&
            t.uvScale == uvScale)
            return int(i);
    }
    if (!fs::exists(path)) {
        addWarning(scene,
                   fmt::format("{}: texture file not found: '{}'; {}", context, path, fallback));
        return -1;
    }
    ImageData image;
    try {
        image = readImage(path, false);
    } catch (const UserError& e) {
        addWarning(scene, fmt::format("{}: cannot read texture '{}' ({}); {}", context, path,
                                      e.what(), fallback));
        return -1;
    }
    // Colour textures in LDR formats are sRGB-encoded whatever their bit depth; float formats
    // (EXR, HDR, PFM) are linear.
    std::string ext = lowerExtension(path);
    bool ldr = ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tga" ||
               ext == ".gif" || ext == ".ppm" || ext == ".webp";
    Texture tex;
    tex.name = fs::path(path).filename().string();
    tex.kind = TextureKind::Bitmap;
    tex.path = path;
    tex.width = image.width;
    tex.height = image.height;
    tex.uvScale = uvScale;
    tex.isNormalMap = raw;
    size_t n = size_t(image.width) * image.height;
    tex.rgba.resize(n * 4);
    uint32_t c = image.channels;
    for (size_t p = 0; p < n; ++p) {
        const float* src = image.pixels.data() + p * c;
        float rgba[4];
        if (c >= 3) {
            rgba[0] = src[0];
            rgba[1] = src[1];
            rgba[2] = src[2];
            rgba[3] = c >= 4 ? src[3] : 1.0f;
        } else {  // grey (+ alpha)
            rgba[0] = rgba[1] = rgba[2] = src[0];
            rgba[3] = c == 2 ? src[1] : 1.0f;
        }
        if (!raw && ldr)
            for (int k = 0; k < 3; ++k) rgba[k] = srgbToLinearFast(rgba[k]);
        std::copy(rgba, rgba + 4, tex.rgba.data() + p * 4);
    }
    scene.textures.push_back(std::move(tex));
    return int(scene.textures.size() - 1);
}

glm::vec3 textureAverage(const Texture& texture) {
    if (texture.kind == TextureKind::Checkerboard) return 0.5f * (texture.color0 + texture.color1);
    if (texture.kind == TextureKind::Constant) return texture.color0;
    size_t n = texture.rgba.size() / 4;
    if (n == 0) return glm::vec3(0.5f);
    glm::dvec3 sum(0.0);
    for (size_t i = 0; i < n; ++i)
        sum += glm::dvec3(texture.rgba[i * 4], texture.rgba[i * 4 + 1], texture.rgba[i * 4 + 2]);
    return glm::vec3(sum / double(n));
}

namespace {

struct ConductorEntry {
    const char* name;
    glm::vec3 eta, k;
};

// RGB complex IORs: Mitsuba's measured spectral data integrated against linear sRGB primaries
// (peaks near 650/550/450 nm), as tabulated in Tungsten's ComplexIorData and used by
// Bitterli's scene conversions (e.g. Al, Cr in veach-ajar/staircase; VN in veach-bidir).
const ConductorEntry kConductors[] = {
    {"a-C",
     {2.9440999183f, 2.2271502925f, 1.9681668794f},
     {0.8874329109f, 0.7993216383f, 0.8152862927f}},
    {"Ag",
     {0.1552646489f, 0.1167232965f, 0.1383806959f},
     {4.8283433224f, 3.1222459278f, 2.1469504455f}},
    {"Al",
     {1.6574599595f, 0.8803689579f, 0.5212287346f},
     {9.2238691996f, 6.2695232477f, 4.8370012281f}},
    {"Au",
     {0.1431189557f, 0.3749570432f, 1.4424785571f},
     {3.9831604247f, 2.3857207478f, 1.6032152899f}},
    {"Be",
     {4.1850592788f, 3.1850604423f, 2.7840913457f},
     {3.8354398268f, 3.0101260162f, 2.8690088743f}},
    {"Cr",
     {4.3696828663f, 2.9167024892f, 1.6547005413f},
     {5.2064337956f, 4.2313645277f, 3.7549467933f}},
    {"Cu",
     {0.2004376970f, 0.9240334304f, 1.1022119527f},
     {3.9129485033f, 2.4528477015f, 2.1421879552f}},
    {"Hg",
     {2.3989314904f, 1.4400254917f, 0.9095512090f},
     {6.3276269444f, 4.3719414152f, 3.4217899270f}},
    {"Ir",
     {3.0864098394f, 2.0821938440f, 1.6178866805f},
     {5.5921510077f, 4.0671757150f, 3.2672611269f}},
    {"K",
     {0.0640493070f, 0.0464100621f, 0.0381842017f},
     {2.1042155920f, 1.3489364357f, 0.9132113889f}},
    {"Li",
     {0.2657871942f, 0.1956102432f, 0.2209198538f},
     {3.5401743407f, 2.3111306542f, 1.6685930000f}},
    {"Mo",
     {4.4837010280f, 3.5254578255f, 2.7760769438f},
     {4.1111307988f, 3.4208716252f, 3.1506031404f}},
    {"Na",
     {0.0602665320f, 0.0561412435f, 0.0619909494f},
     {3.1792906496f, 2.1124800781f, 1.5790940266f}},
    {"Nb",
     {3.4201353595f, 2.7901921379f, 2.3955856658f},
     {3.4413817900f, 2.7376437930f, 2.5799132708f}},
    {"Ni",
     {2.3672753521f, 1.6633583302f, 1.4670554172f},
     {4.4988329911f, 3.0501643957f, 2.3454274399f}},
    {"Rh",
     {2.5857954933f, 1.8601866068f, 1.5544279524f},
     {6.7822927110f, 4.7029501026f, 3.9760892461f}},
    {"Ta",
     {2.0625846607f, 2.3930915569f, 2.6280684948f},
     {2.4080467973f, 1.7413705864f, 1.9470377016f}},
    {"TiC",
     {3.7004673762f, 2.8374356509f, 2.5823030278f},
     {3.2656905818f, 2.3515586388f, 2.1727857800f}},
    {"TiN",
     {1.6484691607f, 1.1504482522f, 1.3797795097f},
     {3.3684596226f, 1.9434888540f, 1.1020123347f}},
    {"V",
     {4.2775126218f, 3.5131538236f, 2.7611257461f},
     {3.4911844504f, 2.8893580874f, 3.1116965117f}},
    {"VC",
     {3.6575665991f, 2.7527298065f, 2.5326814570f},
     {3.0683516659f, 2.1986687713f, 1.9631816252f}},
    {"VN",
     {2.8656011588f, 2.1191817791f, 1.9400767149f},
     {3.0323264950f, 2.0561075580f, 1.6162930914f}},
    {"W",
     {4.3707029924f, 3.3002972445f, 2.9982666528f},
     {3.5006778591f, 2.6048652781f, 2.2731930614f}},
    // Perfect mirror: |r| = 1 at every angle for eta = 0, k = 1.
    {"none", {0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}},
};

}  // namespace

bool conductorIor(const std::string& name, glm::vec3& eta, glm::vec3& k) {
    std::string n = name;
    // Mitsuba 3 also ships Palik variants of some metals; the RGB values are the same within
    // the precision that matters here.
    if (n.size() > 6 && n.substr(n.size() - 6) == "_palik") n = n.substr(0, n.size() - 6);
    for (const ConductorEntry& e : kConductors)
        if (n == e.name) {
            eta = e.eta;
            k = e.k;
            return true;
        }
    return false;
}

std::string conductorNames() {
    std::string s;
    for (const ConductorEntry& e : kConductors) s += (s.empty() ? "" : ", ") + std::string(e.name);
    return s;
}

bool namedIor(const std::string& name, float& ior) {
    // Mitsuba's documented table of named interior/exterior IORs.
    static const std::pair<const char*, float> kIors[] = {
        {"vacuum", 1.0f},      {"helium", 1.00004f},         {"hydrogen", 1.00013f},
        {"air", 1.00028f},     {"carbon dioxide", 1.00045f}, {"water", 1.3330f},
        {"acetone", 1.36f},    {"ethanol", 1.361f},          {"carbon tetrachloride", 1.461f},
        {"glycerol", 1.4729f}, {"benzene", 1.501f},          {"silicone oil", 1.52045f},
        {"bromine", 1.661f},   {"water ice", 1.31f},         {"fused quartz", 1.458f},
        {"pyrex", 1.470f},     {"acrylic glass", 1.49f},     {"polypropylene", 1.49f},
        {"bk7", 1.5046f},      {"sodium chloride", 1.544f},  {"amber", 1.55f},
        {"pet", 1.5750f},      {"diamond", 2.419f}};
    std::string n = name;
    std::transform(n.begin(), n.end(), n.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    for (auto& [key, value] : kIors)
        if (n == key) {
            ior = value;
            return true;
        }
    return false;
}

namespace {

std::string formatVec(const glm::vec3& v) {
    return fmt::format("({}, {}, {})", v.x, v.y, v.z);
}

// The range rules, once for all loaders.
void checkPhysicalRanges(Scene& scene) {
    auto at = [&](const std::string& origin, const std::string& what) {
        return (origin.empty() ? scene.sourceFile : origin) + ": " + what;
    };
    auto finite = [](const glm::vec3& v) {
        return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    auto nonNegative = [&](const glm::vec3& v, const std::string& where, const char* name) {
        if (!finite(v))
            throw UserError(fmt::format("{}: {} {} is not finite", where, name, formatVec(v)));
        if (v.x < 0.0f || v.y < 0.0f || v.z < 0.0f)
            throw UserError(fmt::format("{}: {} {} is negative", where, name, formatVec(v)));
    };
    auto albedo = [&](const glm::vec3& v, const std::string& where, const char* name) {
        nonNegative(v, where, name);
        if (v.x > 1.0f || v.y > 1.0f || v.z > 1.0f)
            addWarning(scene, fmt::format("{}: {} {} exceeds 1: the surface reflects more light "
                                          "than it receives",
                                          where, name, formatVec(v)));
    };
    auto number = [&](float x, const std::string& where, const char* name, float lo, bool loOpen) {
        if (!std::isfinite(x) || x < lo || (loOpen && x == lo))
            throw UserError(fmt::format("{}: {} = {} must be a finite number {} {}", where, name, x,
                                        loOpen ? ">" : ">=", lo));
    };
    for (const Material& m : scene.materials) {
        std::string where = at(m.origin, "material '" + m.name + "'");
        albedo(m.reflectance, where, "reflectance");
        albedo(m.specularReflectance, where, "specular reflectance");
        albedo(m.specularTransmittance, where, "specular transmittance");
        number(m.alpha, where, "roughness alpha", 0.0f, false);
        number(m.eta, where, "index of refraction", 0.0f, true);
        nonNegative(m.conductorEta, where, "conductor eta");
        nonNegative(m.conductorK, where, "conductor k");
    }
    bool emits = false;
    for (const Shape& s : scene.shapes) {
        nonNegative(s.emission, at(s.origin, "shape '" + s.name + "'"), "emitted radiance");
        if (s.emission.x + s.emission.y + s.emission.z <= 0.0f) continue;
        double area = 0.0;
        const Mesh& mesh = scene.meshes[size_t(s.mesh)];
        for (const auto& tri : mesh.indices) {
            glm::vec3 a(s.toWorld * glm::vec4(mesh.positions[tri.x], 1.0f));
            glm::vec3 b(s.toWorld * glm::vec4(mesh.positions[tri.y], 1.0f));
            glm::vec3 c(s.toWorld * glm::vec4(mesh.positions[tri.z], 1.0f));
            area += 0.5 * double(glm::length(glm::cross(b - a, c - a)));
        }
        if (area > 0.0)
            emits = true;
        else
            addWarning(scene, at(s.origin, "shape '" + s.name +
                                               "': an emitter with zero area emits nothing"));
    }
    for (const Light& l : scene.lights) {
        std::string where = at(l.origin, "light");
        nonNegative(l.intensity, where, "intensity");
        number(l.scale, where, "scale", 0.0f, false);
        if (l.type == LightType::Spot &&
            !(l.cutoffAngle > 0.0f && l.cutoffAngle <= 180.0f && std::isfinite(l.beamWidth)))
            throw UserError(
                fmt::format("{}: spot cutoff angle {} must be in (0, 180]", where, l.cutoffAngle));
        if ((l.type == LightType::Spot || l.type == LightType::Directional) &&
            !(finite(l.direction) && glm::length(l.direction) > 0.0f))
            throw UserError(where + ": direction " + formatVec(l.direction) + " is not usable");
        if (l.intensity.x + l.intensity.y + l.intensity.z > 0.0f && l.scale > 0.0f) emits = true;
    }
    auto checkFov = [&](float fov, const std::string& what) {
        if (!(fov > 0.0f && fov < 180.0f))
            throw UserError(fmt::format("{}: camera {} = {} degrees must be in (0, 180)",
                                        scene.sourceFile, what, fov));
    };
    checkFov(scene.camera.fov, "fov");
    for (const CameraKeyframe& k : scene.camera.path) checkFov(k.fovY, "path fov");
    if (!emits)
        addWarning(scene, scene.sourceFile +
                              ": the scene has no emitter that can emit light (no light, or only "
                              "zero-area or black emitters); lit images will be black");
}

}  // namespace

void setDefaultCamera(Scene& scene) {
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const Shape& s : scene.shapes) {
        if (s.mesh < 0 || s.mesh >= int(scene.meshes.size())) continue;
        for (const glm::vec3& p : scene.meshes[s.mesh].positions) {
            glm::vec3 w = glm::vec3(s.toWorld * glm::vec4(p, 1.0f));
            lo = glm::min(lo, w);
            hi = glm::max(hi, w);
        }
    }
    if (lo.x > hi.x) lo = hi = glm::vec3(0.0f);
    glm::vec3 center = 0.5f * (lo + hi);
    float radius = std::max(0.5f * glm::length(hi - lo), 1e-3f);
    Camera& cam = scene.camera;
    cam = Camera{};
    cam.fov = 40.0f;
    cam.fovAxis = Camera::FovAxis::Y;
    // Far enough that the bounding sphere fits the vertical fov (sin(20 deg) ~ 0.34).
    cam.toWorld = lookAtMatrix(center + glm::vec3(0, 0, 3.0f * radius), center, glm::vec3(0, 1, 0));
}

void validateScene(Scene& scene) {
    const std::string& file = scene.sourceFile;
    for (size_t i = 0; i < scene.meshes.size(); ++i)
        validateMesh(scene.meshes[i], fmt::format("{}: mesh '{}'", file, scene.meshes[i].name));
    auto checkIndex = [&](int index, size_t size, const std::string& what) {
        if (index < -1 || index >= int(size))
            throw UserError(fmt::format("{}: internal loader error: {} index {} out of range ({})",
                                        file, what, index, size));
    };
    for (const Shape& s : scene.shapes) {
        if (s.mesh < 0) throw UserError(fmt::format("{}: shape '{}' has no mesh", file, s.name));
        checkIndex(s.mesh, scene.meshes.size(), "mesh of shape '" + s.name + "'");
        checkIndex(s.material, scene.materials.size(), "material of shape '" + s.name + "'");
    }
    for (const Material& m : scene.materials) {
        checkIndex(m.reflectanceTexture, scene.textures.size(),
                   "texture of material '" + m.name + "'");
        checkIndex(m.normalMap, scene.textures.size(), "normal map of material '" + m.name + "'");
        checkIndex(m.specularReflectanceTexture, scene.textures.size(),
                   "specular texture of material '" + m.name + "'");
    }
    for (const Light& l : scene.lights)
        checkIndex(l.envTexture, scene.textures.size(), "environment texture");
    checkPhysicalRanges(scene);
}

}  // namespace detail
}  // namespace loom::scene
