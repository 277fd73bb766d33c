// Scene loaders: every shared Mitsuba scene and every project JSON scene loads; specific values
// of known scenes; error messages; Mitsuba transform composition; PLY encodings; glTF/OBJ.
#include "core/scene/SceneLoader.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "core/scene/Camera.h"
#include "core/scene/Shapes.h"
#include "core/util/Error.h"

namespace {

namespace fs = std::filesystem;
using namespace loom::scene;

fs::path sharedScenes() {
    return fs::path(LOOM_SOURCE_DIR) / ".." / "shared" / "scenes";
}

// A fresh directory under the system temp dir, removed at the end of the test.
class TempDir {
public:
    TempDir() {
        static std::atomic<int> counter{0};
        mPath = fs::temp_directory_path() /
                ("loom_scene_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        fs::create_directories(mPath);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(mPath, ec);
    }
    std::string write(const std::string& name, const std::string& text) const {
        fs::path p = mPath / name;
        std::ofstream(p, std::ios::binary) << text;
        return p.string();
    }
    const fs::path& path() const { return mPath; }

private:
    fs::path mPath;
};

bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool finite(const glm::mat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}

size_t triangleCount(const Scene& s) {
    size_t n = 0;
    for (const Shape& shape : s.shapes) n += s.meshes[size_t(shape.mesh)].indices.size();
    return n;
}

// Structural checks every loaded scene must pass.
void expectSane(const Scene& s, const std::string& what) {
    SCOPED_TRACE(what);
    EXPECT_GT(s.shapes.size(), 0u);
    EXPECT_GT(s.camera.fov, 0.0f);
    EXPECT_LT(s.camera.fov, 180.0f);
    EXPECT_TRUE(finite(s.camera.toWorld));
    bool emissive = false;
    for (const Shape& shape : s.shapes) {
        ASSERT_GE(shape.mesh, 0);
        ASSERT_LT(size_t(shape.mesh), s.meshes.size());
        ASSERT_GE(shape.material, 0);
        ASSERT_LT(size_t(shape.material), s.materials.size());
        EXPECT_TRUE(finite(shape.toWorld)) << shape.name;
        emissive |= glm::length(shape.emission) > 0.0f;
    }
    EXPECT_TRUE(emissive || !s.lights.empty()) << "no light or emissive shape";
    for (const Mesh& m : s.meshes) {
        EXPECT_FALSE(m.indices.empty()) << m.name;
        for (const glm::vec3& p : m.positions) ASSERT_TRUE(finite(p)) << m.name;
        for (const glm::uvec3& t : m.indices)
            ASSERT_TRUE(t.x < m.positions.size() && t.y < m.positions.size() &&
                        t.z < m.positions.size())
                << m.name;
        if (!m.normals.empty()) {
            EXPECT_EQ(m.normals.size(), m.positions.size()) << m.name;
        }
        if (!m.uvs.empty()) {
            EXPECT_EQ(m.uvs.size(), m.positions.size()) << m.name;
        }
    }
    for (const Material& m : s.materials) {
        EXPECT_LT(m.reflectanceTexture, int(s.textures.size()));
        EXPECT_LT(m.normalMap, int(s.textures.size()));
    }
}

const Shape* shapeNamed(const Scene& s, const std::string& name) {
    for (const Shape& shape : s.shapes)
        if (shape.name == name) return &shape;
    return nullptr;
}

std::string loadError(const std::string& path) {
    try {
        loadScene(path);
    } catch (const loom::UserError& e) {
        return e.what();
    }
    return "";
}

void expectNear(const glm::vec3& a, const glm::vec3& b, float eps = 1e-4f) {
    EXPECT_NEAR(a.x, b.x, eps);
    EXPECT_NEAR(a.y, b.y, eps);
    EXPECT_NEAR(a.z, b.z, eps);
}

glm::vec3 apply(const glm::mat4& m, const glm::vec3& p) {
    return glm::vec3(m * glm::vec4(p, 1.0f));
}

// ------------------------------------------------------------------------------------------
// (a) every shared Mitsuba scene

TEST(SceneLoaders, AllSharedMitsubaScenesLoad) {
    if (!fs::is_directory(sharedScenes())) GTEST_SKIP() << "no shared scenes at " << sharedScenes();
    // PROVENANCE.md: sms-slab is incomplete (meshes/plane_1.obj could not be obtained) and the
    // unedited originals of two Bitterli scenes reference OBJs that were replaced by PLYs. These
    // must fail with an error naming the missing mesh (until the files are added).
    const std::map<std::string, std::string> kIncomplete = {
        {"sms-slab/slab_pt.xml", "plane_1.obj"},
        {"sms-slab/slab_sms.xml", "plane_1.obj"},
        {"veach-ajar/scene_original_obj-teapots.xml", "models/Mesh00"},
        {"water-caustic/scene_original_obj.xml", "models/Mesh001.obj"}};
    std::vector<fs::path> files;
    for (const auto& dir : fs::directory_iterator(sharedScenes()))
        if (dir.is_directory())
            for (const auto& f : fs::directory_iterator(dir.path()))
                if (f.path().extension() == ".xml") files.push_back(f.path());
    std::sort(files.begin(), files.end());
    ASSERT_FALSE(files.empty());
    // The SMS roughness sweep (sms-plane/plane_rough_*.xml) takes alpha on the command line
    // (mitsuba -Dalpha=...); defines override <default> and are ignored where unused.
    SceneLoadOptions options;
    options.defines["alpha"] = "0.05";
    for (const fs::path& file : files) {
        std::string rel = file.parent_path().filename().string() + "/" + file.filename().string();
        SCOPED_TRACE(rel);
        try {
            Scene s = loadScene(file.string(), options);
            expectSane(s, rel);
            std::printf("[scene] %-55s shapes %4zu  triangles %8zu  lights %zu  warnings %zu\n",
                        rel.c_str(), s.shapes.size(), triangleCount(s), s.lights.size(),
                        s.warnings.size());
        } catch (const loom::UserError& e) {
            auto it = kIncomplete.find(rel);
            ASSERT_TRUE(it != kIncomplete.end()) << e.what();
            EXPECT_NE(std::string(e.what()).find(it->second), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos) << e.what();
            std::printf("[scene] %-55s incomplete (documented): %s\n", rel.c_str(), e.what());
        }
    }
}

// ------------------------------------------------------------------------------------------
// (b) specific scenes

TEST(SceneLoaders, CornellBox) {
    fs::path file = sharedScenes() / "cornell-box" / "scene.xml";
    if (!fs::exists(file)) GTEST_SKIP();
    Scene s = loadScene(file.string());
    EXPECT_EQ(s.shapes.size(), 8u);
    const Shape* light = shapeNamed(s, "Light");
    ASSERT_NE(light, nullptr);
    expectNear(light->emission, glm::vec3(17, 12, 4));
    for (const Shape& shape : s.shapes)
        if (shape.name != "Light") {
            EXPECT_EQ(glm::length(shape.emission), 0.0f) << shape.name;
        }
    EXPECT_FLOAT_EQ(s.camera.fov, 19.5f);
    EXPECT_EQ(s.camera.fovAxis, Camera::FovAxis::X);
    EXPECT_EQ(s.camera.filmWidth, 1024u);
    // The light rectangle faces down (-y) into the box.
    glm::vec3 n = glm::normalize(glm::vec3(light->toWorld * glm::vec4(0, 0, 1, 0)));
    EXPECT_LT(n.y, -0.99f);
    const Material& left = s.materials[size_t(shapeNamed(s, "LeftWall")->material)];
    EXPECT_TRUE(left.twoSided);
    expectNear(left.reflectance, glm::vec3(0.63f, 0.065f, 0.05f));
    EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
}

TEST(SceneLoaders, VeachAjarCamera) {
    fs::path file = sharedScenes() / "veach-ajar" / "scene.xml";
    if (!fs::exists(file)) GTEST_SKIP();
    Scene s = loadScene(file.string());
    EXPECT_FLOAT_EQ(s.camera.fov, 60.0f);
    EXPECT_EQ(s.camera.fovAxis, Camera::FovAxis::X);
    EXPECT_EQ(s.camera.filmWidth, 1280u);
    EXPECT_EQ(s.camera.filmHeight, 720u);
    expectNear(glm::vec3(s.camera.toWorld[3]), glm::vec3(4.05402f, 1.61647f, -2.30652f));
    // The floor's checkerboard specular reflectance is kept as a texture.
    const Material& floor = s.materials[size_t(shapeNamed(s, "Floor")->material)];
    EXPECT_EQ(floor.type, BsdfType::RoughConductor);
    ASSERT_GE(floor.specularReflectanceTexture, 0);
    EXPECT_EQ(s.textures[size_t(floor.specularReflectanceTexture)].kind, TextureKind::Checkerboard);
    expectNear(glm::vec3(s.textures[size_t(floor.specularReflectanceTexture)].uvScale, 0),
               glm::vec3(20, 80, 0));
    // Teapots share two PLY meshes.
    EXPECT_EQ(shapeNamed(s, "Pot2_0001")->mesh, shapeNamed(s, "Pot3_0002")->mesh);
}

TEST(SceneLoaders, WaterCausticMitsuba05Names) {
    fs::path file = sharedScenes() / "water-caustic" / "scene.xml";
    if (!fs::exists(file)) GTEST_SKIP();
    Scene s = loadScene(file.string());
    // toWorld, intIOR/extIOR, faceNormals, fileFormat, sampleCount... are all understood or
    // knowingly ignored: no "unsupported property" warning.
    for (const std::string& w : s.warnings) EXPECT_EQ(w.find("property '"), std::string::npos) << w;
    int water = 0;
    for (const Shape& shape : s.shapes) {
        const Material& m = s.materials[size_t(shape.material)];
        if (m.type != BsdfType::Dielectric) continue;
        ++water;
        EXPECT_NEAR(m.eta, 1.8f, 1e-5f);             // intIOR 1.8 / extIOR 1
        EXPECT_FLOAT_EQ(shape.toWorld[1][1], 1.5f);  // toWorld matrix
        if (shape.name == "Mesh000") {
            EXPECT_TRUE(s.meshes[size_t(shape.mesh)].faceNormals);  // faceNormals
        }
    }
    EXPECT_EQ(water, 2);
    EXPECT_FLOAT_EQ(s.camera.fov, 19.5f);
    EXPECT_EQ(s.camera.filmWidth, 1024u);
    expectNear(glm::vec3(s.camera.toWorld[3]), glm::vec3(-1.03263e-06f, 0.990944f, 6.83879f));
}

TEST(SceneLoaders, SmsCausticTags) {
    fs::path ring = sharedScenes() / "sms-ring" / "ring.xml";
    if (!fs::exists(ring)) GTEST_SKIP();
    Scene s = loadScene(ring.string());
    uint32_t all = 0;
    for (const Shape& shape : s.shapes) all |= shape.flags;
    EXPECT_TRUE(all & kCausticCasterReflect);
    EXPECT_TRUE(all & kCausticReceiver);
    EXPECT_TRUE(all & kCausticEmitter);
    EXPECT_FALSE(all & kCausticCasterRefract);
    for (const Shape& shape : s.shapes)
        if (shape.flags & kCausticCasterReflect) {
            const Material& m = s.materials[size_t(shape.material)];
            EXPECT_EQ(m.type, BsdfType::Conductor);
            EXPECT_TRUE(m.twoSided);
            expectNear(m.conductorEta,
                       glm::vec3(0.1431189557f, 0.3749570432f, 1.4424785571f));  // Au
        }

    fs::path sphere = sharedScenes() / "sms-sphere" / "sphere_sms_constfloor.xml";
    if (fs::exists(sphere)) {
        Scene t = loadScene(sphere.string());
        bool refract = false;
        for (const Shape& shape : t.shapes)
            if (shape.flags & kCausticCasterRefract) {
                refract = true;
                const Material& m = t.materials[size_t(shape.material)];
                EXPECT_EQ(m.type, BsdfType::Dielectric);
                ASSERT_GE(m.normalMap, 0);
                EXPECT_TRUE(t.textures[size_t(m.normalMap)].isNormalMap);
                EXPECT_EQ(t.textures[size_t(m.normalMap)].uvScale, glm::vec2(1.0f));  // tiles = 1
            }
        EXPECT_TRUE(refract);
    }
    fs::path pool = sharedScenes() / "sms-pool-lite" / "pool_sms_complete.xml";
    if (fs::exists(pool)) {
        Scene p = loadScene(pool.string());
        ASSERT_EQ(p.lights.size(), 1u);
        EXPECT_EQ(p.lights[0].type, LightType::Environment);
        EXPECT_TRUE(p.lights[0].flags & kCausticEmitter);
        EXPECT_FLOAT_EQ(p.lights[0].scale, 0.4f);
    }
}

// ------------------------------------------------------------------------------------------
// (c) every project JSON scene

TEST(SceneLoaders, AllProjectJsonScenesLoad) {
    fs::path dir = fs::path(LOOM_SOURCE_DIR) / "scenes";
    int count = 0;
    for (const auto& f : fs::directory_iterator(dir)) {
        if (f.path().extension() != ".json") continue;
        ++count;
        std::string name = f.path().filename().string();
        Scene s = loadScene(f.path().string());
        expectSane(s, name);
        EXPECT_TRUE(s.warnings.empty()) << name << ": " << s.warnings.front();
        EXPECT_GE(s.camera.path.size(), 2u) << name;
        EXPECT_LE(triangleCount(s), 20000u) << name;  // project scenes stay small
        std::printf("[scene] %-28s shapes %3zu  triangles %6zu  lights %zu  keyframes %zu\n",
                    name.c_str(), s.shapes.size(), triangleCount(s), s.lights.size(),
                    s.camera.path.size());
    }
    EXPECT_GE(count, 6);
}

TEST(SceneLoaders, JsonSceneContents) {
    Scene s =
        loadScene((fs::path(LOOM_SOURCE_DIR) / "scenes" / "refractive_caustic.json").string());
    uint32_t all = 0;
    for (const Shape& shape : s.shapes) all |= shape.flags;
    EXPECT_TRUE(all & kCausticCasterRefract);
    EXPECT_TRUE(all & kCausticReceiver);
    Scene g = loadScene((fs::path(LOOM_SOURCE_DIR) / "scenes" / "glossy_spheres.json").string());
    float lo = 1.0f, hi = 0.0f;
    for (const Material& m : g.materials)
        if (m.type == BsdfType::RoughConductor || m.type == BsdfType::RoughPlastic) {
            lo = std::min(lo, m.alpha);
            hi = std::max(hi, m.alpha);
        }
    EXPECT_FLOAT_EQ(lo, 0.05f);
    EXPECT_FLOAT_EQ(hi, 0.6f);
    Scene f = loadScene((fs::path(LOOM_SOURCE_DIR) / "scenes" / "fine_geometry.json").string());
    EXPECT_TRUE(std::any_of(f.shapes.begin(), f.shapes.end(),
                            [](const Shape& x) { return x.path.size() == 4; }));
}

// ------------------------------------------------------------------------------------------
// (d) error messages

TEST(SceneLoaders, ErrorMalformedXml) {
    TempDir tmp;
    std::string path =
        tmp.write("bad.xml", "<scene version=\"3.0.0\">\n  <shape type=\"obj\">\n</scene>\n");
    std::string e = loadError(path);
    EXPECT_NE(e.find("bad.xml:3:"), std::string::npos) << e;
    EXPECT_NE(e.find("XML syntax error"), std::string::npos) << e;
}

TEST(SceneLoaders, ErrorUnknownRefId) {
    TempDir tmp;
    std::string path = tmp.write("ref.xml",
                                 "<scene version=\"3.0.0\">\n"
                                 "  <bsdf type=\"diffuse\" id=\"white\"/>\n"
                                 "  <shape type=\"rectangle\">\n"
                                 "    <ref id=\"whte\"/>\n"
                                 "  </shape>\n"
                                 "</scene>\n");
    std::string e = loadError(path);
    EXPECT_NE(e.find("ref.xml:4"), std::string::npos) << e;
    EXPECT_NE(e.find("unknown id 'whte'"), std::string::npos) << e;
    EXPECT_NE(e.find("white"), std::string::npos) << e;  // lists the defined ids
}

TEST(SceneLoaders, ErrorMissingMeshFile) {
    TempDir tmp;
    std::string path = tmp.write("mesh.xml",
                                 "<scene version=\"2.0.0\">\n"
                                 "  <shape type=\"obj\">\n"
                                 "    <string name=\"filename\" value=\"meshes/nothere.obj\"/>\n"
                                 "  </shape>\n"
                                 "</scene>\n");
    std::string e = loadError(path);
    EXPECT_NE(e.find("mesh.xml:3"), std::string::npos) << e;
    EXPECT_NE(e.find("not found"), std::string::npos) << e;
    EXPECT_NE(e.find((tmp.path() / "meshes" / "nothere.obj").string()), std::string::npos) << e;

    std::string json =
        tmp.write("mesh.json",
                  "{\n  \"shapes\": [\n    {\"type\": \"mesh\", \"file\": \"gone.ply\"}\n  ]\n}\n");
    e = loadError(json);
    EXPECT_NE(e.find("mesh.json:3:"), std::string::npos) << e;
    EXPECT_NE(e.find((tmp.path() / "gone.ply").string()), std::string::npos) << e;
}

TEST(SceneLoaders, ErrorMalformedJson) {
    TempDir tmp;
    std::string path =
        tmp.write("bad.json", "{\n  \"shapes\": [\n    {\"type\": \"cube\",, }\n  ]\n}\n");
    std::string e = loadError(path);
    EXPECT_NE(e.find("bad.json:3:"), std::string::npos) << e;
    EXPECT_NE(e.find("syntax error"), std::string::npos) << e;
}

TEST(SceneLoaders, ErrorUnknownJsonKey) {
    TempDir tmp;
    std::string path = tmp.write("key.json",
                                 "{\n"
                                 "  \"shapes\": [\n"
                                 "    {\"type\": \"cube\",\n"
                                 "     \"colour\": [1, 0, 0]}\n"
                                 "  ]\n"
                                 "}\n");
    std::string e = loadError(path);
    EXPECT_NE(e.find("key.json:4:6"), std::string::npos) << e;
    EXPECT_NE(e.find("unknown key 'colour'"), std::string::npos) << e;
    EXPECT_NE(e.find("valid keys:"), std::string::npos) << e;
    EXPECT_NE(e.find("material"), std::string::npos) << e;

    std::string top = tmp.write("top.json", "{\"shapes\": [{\"type\": \"cube\"}], \"lightz\": []}");
    e = loadError(top);
    EXPECT_NE(e.find("unknown key 'lightz'"), std::string::npos) << e;
    EXPECT_NE(e.find("lights"), std::string::npos) << e;
}

TEST(SceneLoaders, ErrorOtherCases) {
    TempDir tmp;
    fs::path rough = sharedScenes() / "sms-plane" / "plane_rough_pt.xml";
    if (fs::exists(rough)) {
        std::string e = loadError(rough.string());
        EXPECT_NE(e.find("plane_rough_pt.xml:60"), std::string::npos) << e;
        EXPECT_NE(e.find("$alpha"), std::string::npos) << e;
        SceneLoadOptions options;
        options.defines["alpha"] = "0.2";
        Scene s = loadScene(rough.string(), options);
        bool found = false;
        for (const Material& m : s.materials)
            found |= m.type == BsdfType::RoughConductor && m.alpha == 0.2f;
        EXPECT_TRUE(found);
    }
    // Undefined $variable names the variable and the line.
    std::string e = loadError(tmp.write("var.xml",
                                        "<scene version=\"3.0.0\">\n"
                                        "  <sensor type=\"perspective\">\n"
                                        "    <float name=\"fov\" value=\"$fov\"/>\n"
                                        "  </sensor>\n</scene>\n"));
    EXPECT_NE(e.find("var.xml:3"), std::string::npos) << e;
    EXPECT_NE(e.find("$fov"), std::string::npos) << e;
    // Bad number in an attribute.
    e = loadError(tmp.write("num.xml",
                            "<scene version=\"3.0.0\">\n"
                            "  <sensor type=\"perspective\">\n"
                            "    <float name=\"fov\" value=\"wide\"/>\n"
                            "  </sensor>\n</scene>\n"));
    EXPECT_NE(e.find("num.xml:3"), std::string::npos) << e;
    EXPECT_NE(e.find("wide"), std::string::npos) << e;
    // Unknown JSON material reference and a bad height formula.
    e = loadError(
        tmp.write("mat.json", "{\"shapes\": [{\"type\": \"cube\", \"material\": \"gold\"}]}"));
    EXPECT_NE(e.find("unknown material 'gold'"), std::string::npos) << e;
    e = loadError(
        tmp.write("hf.json", "{\"shapes\": [{\"type\": \"heightfield\", \"height\": \"sin(x\"}]}"));
    EXPECT_NE(e.find("formula"), std::string::npos) << e;
    EXPECT_NE(loadError((tmp.path() / "nothing.json").string()).find("not found"),
              std::string::npos);
    EXPECT_NE(loadError(tmp.write("scene.fbx", "")).find("unknown scene format"),
              std::string::npos);
}

TEST(SceneLoaders, UnsupportedFeaturesWarnOnce) {
    TempDir tmp;
    std::string path =
        tmp.write("warn.xml",
                  "<scene version=\"3.0.0\">\n"
                  "  <integrator type=\"path\"/>\n"
                  "  <shape type=\"rectangle\">\n"
                  "    <bsdf type=\"roughconductor\">\n"
                  "      <float name=\"alpha_u\" value=\"0.1\"/>\n"
                  "      <float name=\"alpha_v\" value=\"0.3\"/>\n"
                  "      <float name=\"sparkle\" value=\"1\"/>\n"
                  "    </bsdf>\n"
                  "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>\n"
                  "  </shape>\n"
                  "  <shape type=\"hair\"/>\n"
                  "</scene>\n");
    Scene s = loadScene(path);
    ASSERT_EQ(s.warnings.size(), 4u);  // anisotropy, sparkle, hair, no sensor
    EXPECT_NE(s.warnings[0].find("warn.xml:4"), std::string::npos) << s.warnings[0];
    EXPECT_NE(s.warnings[0].find("average"), std::string::npos) << s.warnings[0];
    EXPECT_NE(s.warnings[1].find("warn.xml:7"), std::string::npos) << s.warnings[1];
    EXPECT_NE(s.warnings[1].find("sparkle"), std::string::npos) << s.warnings[1];
    EXPECT_NE(s.warnings[2].find("hair"), std::string::npos) << s.warnings[2];
    EXPECT_NEAR(s.materials[0].alpha, 0.2f, 1e-6f);
}

// ------------------------------------------------------------------------------------------
// (e) Mitsuba transform composition

TEST(SceneLoaders, MitsubaTransformsCompose) {
    TempDir tmp;
    std::string path = tmp.write(
        "xf.xml",
        "<scene version=\"3.0.0\">\n"
        "  <sensor type=\"perspective\">\n"
        "    <float name=\"fov\" value=\"30\"/>\n"
        "    <transform name=\"to_world\">\n"
        "      <lookat origin=\"0, 0, 0\" target=\"1, 0, 0\" up=\"0, 1, 0\"/>\n"
        "      <translate x=\"-3\"/>\n"
        "    </transform>\n"
        "  </sensor>\n"
        "  <shape type=\"rectangle\">\n"
        "    <transform name=\"to_world\">\n"
        "      <scale x=\"2\" y=\"3\"/>\n"
        "      <rotate y=\"1\" angle=\"90\"/>\n"
        "      <translate x=\"1\" y=\"2\" z=\"3\"/>\n"
        "    </transform>\n"
        "    <emitter type=\"area\"><spectrum name=\"radiance\" value=\"5\"/></emitter>\n"
        "  </shape>\n"
        "  <shape type=\"sphere\">\n"
        "    <point name=\"center\" value=\"1, 1, 1\"/>\n"
        "    <float name=\"radius\" value=\"0.5\"/>\n"
        "    <transform name=\"to_world\"><rotate value=\"0, 0, 1\" angle=\"90\"/></transform>\n"
        "  </shape>\n"
        "</scene>\n");
    Scene s = loadScene(path);
    // Ops apply in document order: T * R * S. (1,0,0) -> S (2,0,0) -> Ry(90) (0,0,-2) -> T.
    expectNear(apply(s.shapes[0].toWorld, {1, 0, 0}), {1, 2, 1});
    expectNear(apply(s.shapes[0].toWorld, {0, 1, 0}), {1, 5, 3});
    expectNear(s.shapes[0].emission, glm::vec3(5.0f));
    // lookat: local +z -> (1,0,0), local +x (left) = cross(up, dir) = (0,0,-1); then translate.
    expectNear(apply(s.camera.toWorld, {0, 0, 1}), {-2, 0, 0});
    expectNear(apply(s.camera.toWorld, {1, 0, 0}), {-3, 0, -1});
    expectNear(apply(s.camera.toWorld, {0, 1, 0}), {-3, 1, 0});
    // Sphere: to_world * translate(center) * scale(radius); Rz(90) maps (1,1,1)+(0.5,0,0).
    expectNear(apply(s.shapes[1].toWorld, {1, 0, 0}), {-1, 1.5f, 1});
}

TEST(SceneLoaders, MitsubaDefaultsAndRefs) {
    TempDir tmp;
    tmp.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
    std::string path = tmp.write(
        "refs.xml",
        "<scene version=\"0.5.0\">\n"
        "  <default name=\"ior\" value=\"1.33\"/>\n"
        "  <texture type=\"checkerboard\" id=\"check\">\n"
        "    <rgb name=\"color0\" value=\"1, 0, 0\"/>\n"
        "  </texture>\n"
        "  <bsdf type=\"diffuse\" id=\"base\">\n"
        "    <ref name=\"reflectance\" id=\"check\"/>\n"
        "  </bsdf>\n"
        "  <bsdf type=\"twosided\" id=\"both\"><ref id=\"base\"/></bsdf>\n"
        "  <bsdf type=\"dielectric\" id=\"glass\"><float name=\"intIOR\" value=\"$ior\"/></bsdf>\n"
        "  <shape type=\"obj\">\n"
        "    <string name=\"filename\" value=\"tri.obj\"/>\n"
        "    <boolean name=\"flipNormals\" value=\"true\"/>\n"
        "    <ref id=\"both\"/>\n"
        "  </shape>\n"
        "  <shape type=\"cube\"><ref id=\"glass\"/>\n"
        "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n"
        "  <emitter type=\"point\"><point name=\"position\" x=\"1\" y=\"2\" z=\"3\"/></emitter>\n"
        "</scene>\n");
    Scene s = loadScene(path);
    const Material& m0 = s.materials[size_t(s.shapes[0].material)];
    EXPECT_TRUE(m0.twoSided);
    ASSERT_GE(m0.reflectanceTexture, 0);
    expectNear(s.textures[size_t(m0.reflectanceTexture)].color0, {1, 0, 0});
    EXPECT_NEAR(s.materials[size_t(s.shapes[1].material)].eta, 1.33f / 1.000277f, 1e-5f);
    // flipNormals reverses the winding and the recomputed normals.
    const Mesh& tri = s.meshes[size_t(s.shapes[0].mesh)];
    EXPECT_EQ(tri.indices[0], glm::uvec3(0, 2, 1));
    expectNear(tri.normals[0], {0, 0, -1});
    expectNear(glm::vec3(tri.uvs[2], 0), {0, 0, 0});  // vt (0,1) flipped to (0,0)
    ASSERT_EQ(s.lights.size(), 1u);
    expectNear(s.lights[0].position, {1, 2, 3});
}

// ------------------------------------------------------------------------------------------
// (f) PLY encodings

std::string plyHeader(const std::string& format) {
    return "ply\nformat " + format +
           " 1.0\ncomment test\nelement vertex 5\nproperty float x\nproperty float y\nproperty "
           "float z\n"
           "property uchar red\nproperty float nx\nproperty float ny\nproperty float nz\n"
           "property float u\nproperty float v\nelement face 2\nproperty list uchar int "
           "vertex_indices\n"
           "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
}

TEST(SceneLoaders, PlyAsciiAndBinaryAgree) {
    const float v[5][8] = {{0, 0, 0, 0, 0, 1, 0, 0},
                           {1, 0, 0, 0, 0, 1, 1, 0},
                           {1, 1, 0, 0, 0, 1, 1, 1},
                           {0, 1, 0, 0, 0, 1, 0, 1},
                           {0.5f, 2.25f, -1.5f, 0.6f, 0, 0.8f, 0.5f, 0.75f}};
    const std::vector<std::vector<int>> faces = {{0, 1, 2, 3}, {3, 2, 4}};
    TempDir tmp;
    // ASCII.
    std::string ascii = plyHeader("ascii");
    for (auto& r : v) {
        char line[256];
        std::snprintf(line, sizeof line, "%g %g %g 255 %g %g %g %g %g\n", r[0], r[1], r[2], r[3],
                      r[4], r[5], r[6], r[7]);
        ascii += line;
    }
    for (auto& f : faces) {
        ascii += std::to_string(f.size());
        for (int i : f) ascii.append(" ").append(std::to_string(i));
        ascii += "\n";
    }
    ascii += "0 1\n";
    // Binary, both byte orders.
    auto binary = [&](bool big) {
        std::string out = plyHeader(big ? "binary_big_endian" : "binary_little_endian");
        auto put = [&](const void* p, size_t n) {
            std::string bytes(static_cast<const char*>(p), n);
            if (big) std::reverse(bytes.begin(), bytes.end());
            out += bytes;
        };
        for (auto& r : v) {
            for (int k = 0; k < 3; ++k) put(&r[k], 4);
            uint8_t red = 255;
            put(&red, 1);
            for (int k = 3; k < 8; ++k) put(&r[k], 4);
        }
        for (auto& f : faces) {
            auto n = uint8_t(f.size());
            put(&n, 1);
            for (int i : f) put(&i, 4);
        }
        int e[2] = {0, 1};
        put(&e[0], 4);
        put(&e[1], 4);
        return out;
    };
    Mesh a = readPly(tmp.write("a.ply", ascii));
    Mesh le = readPly(tmp.write("le.ply", binary(false)));
    Mesh be = readPly(tmp.write("be.ply", binary(true)));
    ASSERT_EQ(a.positions.size(), 5u);
    ASSERT_EQ(a.indices.size(), 3u);  // quad fan + triangle
    EXPECT_EQ(a.indices[0], glm::uvec3(0, 1, 2));
    EXPECT_EQ(a.indices[1], glm::uvec3(0, 2, 3));
    for (const Mesh* m : {&le, &be}) {
        EXPECT_EQ(m->positions, a.positions);
        EXPECT_EQ(m->normals, a.normals);
        EXPECT_EQ(m->uvs, a.uvs);
        EXPECT_EQ(m->indices, a.indices);
    }
    expectNear(a.positions[4], {0.5f, 2.25f, -1.5f});
    expectNear(glm::vec3(a.uvs[4], 0), {0.5f, 0.75f, 0});
    // Truncated binary data and bad indices are errors naming the file.
    std::string truncated = binary(false);
    truncated.resize(truncated.size() - 6);
    EXPECT_THROW(readPly(tmp.write("t.ply", truncated)), loom::UserError);
    std::string badIndex = ascii;
    badIndex.replace(badIndex.find("3 3 2 4"), 7, "3 3 2 9");
    try {
        readPly(tmp.write("bad.ply", badIndex));
        ADD_FAILURE() << "expected an error";
    } catch (const loom::UserError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.ply"), std::string::npos) << e.what();
    }
}

// ------------------------------------------------------------------------------------------
// Built-in shapes, camera paths, glTF and OBJ scenes

TEST(SceneLoaders, BuiltinShapesAreOutwardAndConsistent) {
    // Vertex normals agree with the triangle winding (geometric normal), so one-sided lights
    // and normal-based tests see the same side as Mitsuba.
    std::vector<Mesh> meshes = {
        makeRectangle(),   makeCube(),
        makeSphere(8, 16), makeDisk(12),
        makeCylinder(12),  makeHeightfield(4, 4, [](float x, float y) { return 0.1f * x * y; })};
    for (const Mesh& m : meshes) {
        validateMesh(m, m.name);
        for (const glm::uvec3& t : m.indices) {
            glm::vec3 g = glm::cross(m.positions[t.y] - m.positions[t.x],
                                     m.positions[t.z] - m.positions[t.x]);
            ASSERT_GT(glm::length(g), 0.0f) << m.name;
            for (int k = 0; k < 3; ++k) EXPECT_GT(glm::dot(g, m.normals[t[k]]), 0.0f) << m.name;
        }
    }
    // Cylinder frame: p0 -> p1 with the given radius.
    glm::mat4 c = cylinderTransform({1, 2, 3}, {1, 2, 7}, 0.5f);
    expectNear(apply(c, {0, 0, 1}), {1, 2, 7});
    EXPECT_NEAR(glm::length(apply(c, {1, 0, 0}) - glm::vec3(1, 2, 3)), 0.5f, 1e-6f);
    // Grass is deterministic.
    GrassParams g;
    g.blades = 50;
    EXPECT_EQ(makeGrass(g).positions, makeGrass(g).positions);
    HeightFormula f = HeightFormula::parse("2 * x ^ 2 - max(y, 0.5) + sin(pi / 2) + -r", "test");
    EXPECT_NEAR(f(1.0f, 0.0f), 2.0f - 0.5f + 1.0f - 1.0f, 1e-5f);
    EXPECT_THROW(HeightFormula::parse("foo(x)", "test"), loom::UserError);
}

TEST(SceneLoaders, CameraPathInterpolates) {
    Camera c;
    c.path = {{0.0f, {0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 30.0f},
              {10.0f, {10, 0, 0}, {10, 0, 1}, {0, 1, 0}, 50.0f}};
    Camera mid = cameraAt(c, 5.0f);
    expectNear(glm::vec3(mid.toWorld[3]), {5, 0, 0});
    EXPECT_FLOAT_EQ(mid.fov, 40.0f);
    EXPECT_EQ(mid.fovAxis, Camera::FovAxis::Y);
    expectNear(glm::vec3(mid.toWorld[2]), {0, 0, 1});
    expectNear(glm::vec3(cameraAt(c, -3.0f).toWorld[3]), {0, 0, 0});
    expectNear(glm::vec3(cameraAt(c, 99.0f).toWorld[3]), {10, 0, 0});
    Camera still;
    still.fov = 12.0f;
    EXPECT_FLOAT_EQ(cameraAt(still, 3.0f).fov, 12.0f);
}

TEST(SceneLoaders, GltfScene) {
    TempDir tmp;
    // One triangle (3 float3 positions, 3 uint16 indices + 2 bytes padding).
    std::string bin;
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint16_t idx[4] = {0, 1, 2, 0};
    bin.append(reinterpret_cast<const char*>(pos), sizeof pos);
    bin.append(reinterpret_cast<const char*>(idx), sizeof idx);
    tmp.write("tri.bin", bin);
    std::string path = tmp.write("tri.gltf", R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_ior"],
  "scene": 0,
  "scenes": [{"nodes": [0, 1, 2]}],
  "nodes": [
    {"mesh": 0, "translation": [0, 0, -2]},
    {"camera": 0, "translation": [0, 0, 3]},
    {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [1, 2, 3]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
  "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0.25, 1], "metallicFactor": 1,
                 "roughnessFactor": 0.5}, "doubleSided": true}],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1, 1, 1], "intensity": 5}]}},
  "buffers": [{"uri": "tri.bin", "byteLength": 44}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 8}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
})");
    Scene s = loadScene(path);
    expectSane(s, "tri.gltf");
    ASSERT_EQ(s.shapes.size(), 1u);
    expectNear(apply(s.shapes[0].toWorld, {1, 0, 0}), {1, 0, -2});
    const Material& m = s.materials[size_t(s.shapes[0].material)];
    EXPECT_EQ(m.type, BsdfType::RoughConductor);
    EXPECT_FLOAT_EQ(m.alpha, 0.25f);
    expectNear(m.specularReflectance, {1, 0.5f, 0.25f});
    EXPECT_TRUE(m.twoSided);
    EXPECT_NEAR(s.camera.fov, glm::degrees(0.5f), 1e-4f);
    // glTF cameras look down -z: Loom's +z axis must map to world -z here.
    expectNear(glm::vec3(s.camera.toWorld[2]), {0, 0, -1});
    ASSERT_EQ(s.lights.size(), 1u);
    expectNear(s.lights[0].position, {1, 2, 3});
    expectNear(s.lights[0].intensity, glm::vec3(5.0f));
}

TEST(SceneLoaders, ObjMtlScene) {
    TempDir tmp;
    tmp.write("s.mtl",
              "newmtl wall\nKd 0.8 0.2 0.2\nillum 1\n"
              "newmtl lamp\nKd 0 0 0\nKe 10 10 10\n"
              "newmtl glass\nillum 7\nNi 1.45\n"
              "newmtl mirror\nKd 0 0 0\nKs 0.9 0.9 0.9\nNs 10000\nillum 3\n");
    std::string path = tmp.write("s.obj",
                                 "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                 "usemtl wall\nf 1 2 3 4\nusemtl lamp\nf 1 2 3\n"
                                 "usemtl glass\nf 1 3 4\nusemtl mirror\nf 2 3 4\n");
    Scene s = loadScene(path);
    expectSane(s, "s.obj");
    ASSERT_EQ(s.shapes.size(), 4u);
    std::map<std::string, const Shape*> byName;
    for (const Shape& shape : s.shapes) byName[shape.name] = &shape;
    EXPECT_EQ(s.meshes[size_t(byName["wall"]->mesh)].indices.size(), 2u);
    expectNear(s.materials[size_t(byName["wall"]->material)].reflectance, {0.8f, 0.2f, 0.2f});
    expectNear(byName["lamp"]->emission, glm::vec3(10.0f));
    EXPECT_EQ(s.materials[size_t(byName["glass"]->material)].type, BsdfType::Dielectric);
    EXPECT_FLOAT_EQ(s.materials[size_t(byName["glass"]->material)].eta, 1.45f);
    EXPECT_EQ(s.materials[size_t(byName["mirror"]->material)].type, BsdfType::RoughConductor);
    EXPECT_LT(s.materials[size_t(byName["mirror"]->material)].alpha, 0.02f);
}

}  // namespace

TEST(SceneLoaders, ShapePathParsesAndInterpolates) {
    TempDir tmp;
    std::string path = tmp.write("moving.json", R"({"loom_scene": 1, "shapes": [
        {"name": "box", "type": "cube", "transform": {"scale": 0.5}, "path": [
            {"time": 0, "translate": [1, 0, 0]},
            {"time": 4, "translate": [3, 0, 0], "rotate": {"axis": [0, 1, 0], "angle": 90},
             "scale": 2}]},
        {"name": "still", "type": "rectangle"}]})");
    Scene s = loadScene(path);
    const Shape* box = shapeNamed(s, "box");
    ASSERT_NE(box, nullptr);
    ASSERT_EQ(box->path.size(), 2u);
    EXPECT_TRUE(shapeNamed(s, "still")->path.empty());
    // Clamped before the first key; object point (1, 0, 0) -> scale 0.5 -> translate.
    expectNear(apply(shapeToWorldAt(*box, -1.0f), {1, 0, 0}), {1.5f, 0, 0});
    // Halfway: translate (2, 0, 0), rotate 45 degrees about y, scale 1.5 (after toWorld).
    const float c = std::cos(glm::radians(45.0f)) * 0.75f;
    expectNear(apply(shapeToWorldAt(*box, 2.0f), {1, 0, 0}), {2.0f + c, 0, -c});
    // Clamped after the last key: 90 degrees about y maps +x to -z.
    expectNear(apply(shapeToWorldAt(*box, 9.0f), {1, 0, 0}), {3, 0, -1});

    std::string bad = tmp.write("bad.json", R"({"loom_scene": 1, "shapes": [
        {"type": "cube", "path": [{"time": 1}, {"time": 1, "translate": [0, 1, 0]}]}]})");
    std::string e = loadError(bad);
    EXPECT_NE(e.find("bad.json:2:"), std::string::npos) << e;
    EXPECT_NE(e.find("keyframe times must increase"), std::string::npos) << e;
    std::string unknown = tmp.write("unknown.json", R"({"loom_scene": 1, "shapes": [
        {"type": "cube", "path": [{"time": 0, "origin": [0, 1, 0]}]}]})");
    e = loadError(unknown);
    EXPECT_NE(e.find("unknown key 'origin'"), std::string::npos) << e;
}
