// Wavefront OBJ (+ MTL) through tinyobjloader: readObjMesh() for Mitsuba/Loom mesh shapes and
// loadObjScene() for an OBJ file used as a whole scene.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include "core/scene/SceneLoader.h"
#include "core/scene/Shapes.h"
#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom::scene {

namespace {

namespace fs = std::filesystem;

// "file.mtl:line" of `newmtl name` in the MTL files the OBJ names (tinyobjloader does not keep
// where a material came from), else the OBJ path.
std::string mtlOrigin(const std::string& objPath, const std::string& name) {
    std::ifstream obj(objPath);
    std::string line;
    while (std::getline(obj, line)) {
        std::istringstream ls(line);
        std::string tag, file;
        if (!(ls >> tag) || tag != "mtllib") continue;
        while (ls >> file) {
            std::string mtlPath = (fs::path(objPath).parent_path() / file).string();
            std::ifstream mtl(mtlPath);
            std::string l;
            for (int n = 1; std::getline(mtl, l); ++n) {
                std::istringstream ms(l);
                std::string t, m;
                if (ms >> t >> m && t == "newmtl" && m == name)
                    return mtlPath + ":" + std::to_string(n);
            }
        }
    }
    return objPath;
}

tinyobj::ObjReader parseObj(const std::string& path) {
    if (!fs::exists(path)) throw UserError(path + ": OBJ file not found");
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    config.mtl_search_path = fs::path(path).parent_path().string();
    tinyobj::ObjReader reader;
    if (!reader.ParseFromFile(path, config)) {
        std::string err = reader.Error();
        while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
        throw UserError(fmt::format("{}: cannot parse OBJ file: {}", path,
                                    err.empty() ? "unknown error" : err));
    }
    return reader;
}

// Unique (position, uv, normal) index triples become vertices (as Mitsuba's OBJ loader does).
struct VertexKey {
    int v, vt, vn;
    bool operator==(const VertexKey& o) const { return v == o.v && vt == o.vt && vn == o.vn; }
};
struct VertexKeyHash {
    size_t operator()(const VertexKey& k) const {
        return std::hash<int64_t>()((int64_t(k.v) * 73856093) ^ (int64_t(k.vt) * 19349663) ^
                                    (int64_t(k.vn) * 83492791));
    }
};

class MeshBuilder {
public:
    MeshBuilder(const tinyobj::attrib_t& attrib, bool flipTexCoords, const std::string& path)
        : mAttrib(attrib), mFlip(flipTexCoords), mPath(path) {}

    void addTriangle(const tinyobj::index_t* idx) {
        glm::uvec3 tri;
        for (int k = 0; k < 3; ++k) tri[k] = vertex(idx[k]);
        mMesh.indices.push_back(tri);
    }
    Mesh finish(const std::string& name) {
        Mesh m = std::move(mMesh);
        m.name = name;
        // Normals/uvs only when every vertex has them.
        if (mMissingNormal) m.normals.clear();
        if (mMissingUv) m.uvs.clear();
        return m;
    }

private:
    const tinyobj::attrib_t& mAttrib;
    bool mFlip;
    const std::string& mPath;
    Mesh mMesh;
    std::unordered_map<VertexKey, uint32_t, VertexKeyHash> mMap;
    bool mMissingNormal = false, mMissingUv = false;

    uint32_t vertex(const tinyobj::index_t& i) {
        VertexKey key{i.vertex_index, i.texcoord_index, i.normal_index};
        auto [it, inserted] = mMap.emplace(key, uint32_t(mMesh.positions.size()));
        if (!inserted) return it->second;
        if (i.vertex_index < 0 || size_t(i.vertex_index) * 3 + 2 >= mAttrib.vertices.size())
            throw UserError(
                fmt::format("{}: face references missing vertex {}", mPath, i.vertex_index + 1));
        const float* p = &mAttrib.vertices[size_t(i.vertex_index) * 3];
        mMesh.positions.push_back({p[0], p[1], p[2]});
        if (i.normal_index >= 0 && size_t(i.normal_index) * 3 + 2 < mAttrib.normals.size()) {
            const float* n = &mAttrib.normals[size_t(i.normal_index) * 3];
            glm::vec3 nn(n[0], n[1], n[2]);
            float len = glm::length(nn);
            mMesh.normals.push_back(len > 0.0f ? nn / len : glm::vec3(0, 0, 1));
        } else {
            mMesh.normals.push_back(glm::vec3(0, 0, 1));
            mMissingNormal = true;
        }
        if (i.texcoord_index >= 0 && size_t(i.texcoord_index) * 2 + 1 < mAttrib.texcoords.size()) {
            const float* t = &mAttrib.texcoords[size_t(i.texcoord_index) * 2];
            mMesh.uvs.push_back({t[0], mFlip ? 1.0f - t[1] : t[1]});
        } else {
            mMesh.uvs.push_back(glm::vec2(0.0f));
            mMissingUv = true;
        }
        return it->second;
    }
};

float maxComponent(const float* c) {
    return std::max({c[0], c[1], c[2]});
}

// Phong exponent -> Beckmann alpha with the same lobe width (Walter et al. 2007, Eq. 30).
float phongToAlpha(float ns) {
    return std::sqrt(2.0f / (std::max(ns, 0.0f) + 2.0f));
}

}  // namespace

Mesh readObjMesh(const std::string& path, bool flipTexCoords) {
    tinyobj::ObjReader reader = parseObj(path);
    if (!reader.Warning().empty()) logDebug("{}: {}", path, reader.Warning());
    MeshBuilder builder(reader.GetAttrib(), flipTexCoords, path);
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const auto& ids = shape.mesh.indices;
        for (size_t f = 0; f + 2 < ids.size(); f += 3) builder.addTriangle(&ids[f]);
    }
    Mesh m = builder.finish(path);
    if (m.indices.empty()) throw UserError(path + ": OBJ file has no faces");
    return m;
}

Scene loadObjScene(const std::string& path) {
    Scene scene;
    scene.sourceFile = path;
    tinyobj::ObjReader reader = parseObj(path);
    std::string dir = fs::path(path).parent_path().string();
    if (!reader.Warning().empty()) {
        std::string w = reader.Warning();
        while (!w.empty() && w.back() == '\n') w.pop_back();
        detail::addWarning(scene, path + ": " + w);
    }
    const auto& mtls = reader.GetMaterials();

    // MTL -> Loom material (the closest lobe; no MTL model maps exactly):
    //  - PBR extension Pm >= 0.5: rough conductor (white mirror Fresnel tinted by Kd), alpha = Pr^2
    //  - illum 4/6/7/9, dissolve d < 1 or a transmission filter Tf: smooth dielectric, eta = Ni
    //    (1.5 when Ni <= 1), transmittance Tf
    //  - illum 3/5 (ray-traced reflection) with black Kd: conductor mirror tinted by Ks, rough
    //    (Beckmann) when Ns gives alpha > 1e-3
    //  - non-black Ks: rough plastic, Kd underneath, Beckmann alpha from Ns, eta = Ni
    //  - otherwise Lambertian Kd. map_Kd -> reflectance texture, norm -> normal map.
    //  - Ke -> the shape's area-light radiance.
    std::vector<Material> materials;
    std::vector<glm::vec3> emission;
    for (size_t i = 0; i < mtls.size(); ++i) {
        const tinyobj::material_t& t = mtls[i];
        std::string ctx = fmt::format("{}: material '{}'", path, t.name);
        Material m;
        m.name = t.name;
        m.origin = mtlOrigin(path, t.name);
        glm::vec3 kd(t.diffuse[0], t.diffuse[1], t.diffuse[2]);
        glm::vec3 ks(t.specular[0], t.specular[1], t.specular[2]);
        glm::vec3 tf(t.transmittance[0], t.transmittance[1], t.transmittance[2]);
        float eta = t.ior > 1.0f ? t.ior : 1.5f;
        bool glass =
            t.illum == 4 || t.illum == 6 || t.illum == 7 || t.illum == 9 || t.dissolve < 1.0f;
        if (t.metallic >= 0.5f) {
            m.type = BsdfType::RoughConductor;
            m.distribution = Microfacet::GGX;
            m.alpha = std::max(t.roughness * t.roughness, 1e-3f);
            m.conductorEta = glm::vec3(0.0f);
            m.conductorK = glm::vec3(1.0f);
            m.specularReflectance = kd;
        } else if (glass) {
            m.type = BsdfType::Dielectric;
            m.eta = eta;
            m.specularTransmittance = maxComponent(t.transmittance) > 0.0f ? tf : glm::vec3(1.0f);
        } else if ((t.illum == 3 || t.illum == 5) && maxComponent(t.diffuse) <= 0.0f) {
            float alpha = phongToAlpha(t.shininess);
            m.type = alpha > 1e-3f ? BsdfType::RoughConductor : BsdfType::Conductor;
            m.distribution = Microfacet::Beckmann;
            m.alpha = alpha;
            m.conductorEta = glm::vec3(0.0f);
            m.conductorK = glm::vec3(1.0f);
            m.specularReflectance = maxComponent(t.specular) > 0.0f ? ks : glm::vec3(1.0f);
        } else if (maxComponent(t.specular) > 0.0f && t.illum != 0 && t.illum != 1) {
            m.type = BsdfType::RoughPlastic;
            m.distribution = Microfacet::Beckmann;
            m.alpha = phongToAlpha(t.shininess);
            m.reflectance = kd;
            m.eta = eta;
        } else {
            m.reflectance = kd;
        }
        if (!t.diffuse_texname.empty()) {
            glm::vec2 scale(t.diffuse_texopt.scale[0], t.diffuse_texopt.scale[1]);
            int tex = detail::addBitmapTexture(scene, detail::resolvePath(dir, t.diffuse_texname),
                                               false, scale, ctx + " map_Kd");
            if (tex >= 0) {
                if (m.type == BsdfType::RoughConductor || m.type == BsdfType::Conductor) {
                    m.specularReflectanceTexture = tex;
                    m.specularReflectance = detail::textureAverage(scene.textures[size_t(tex)]);
                } else {
                    m.reflectanceTexture = tex;
                    m.reflectance = detail::textureAverage(scene.textures[size_t(tex)]);
                }
            }
        }
        if (!t.normal_texname.empty()) {
            m.normalMap =
                detail::addBitmapTexture(scene, detail::resolvePath(dir, t.normal_texname), true,
                                         glm::vec2(1.0f), ctx + " norm");
            m.normalMapUseSlopes = false;
        }
        if (!t.bump_texname.empty())
            detail::addWarning(scene,
                               ctx + ": bump maps (map_bump/bump) are not supported; ignored");
        materials.push_back(m);
        emission.push_back(glm::vec3(t.emission[0], t.emission[1], t.emission[2]));
    }

    // One shape per material (faces grouped across OBJ objects).
    std::map<int, MeshBuilder> builders;
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const auto& ids = shape.mesh.indices;
        for (size_t f = 0; f * 3 + 2 < ids.size(); ++f) {
            int mat = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
            if (mat >= int(materials.size())) mat = -1;
            auto it = builders.try_emplace(mat, reader.GetAttrib(), true, path).first;
            it->second.addTriangle(&ids[f * 3]);
        }
    }
    int defaultMaterial = -1;
    for (auto& [mat, builder] : builders) {
        std::string name = mat >= 0 ? materials[size_t(mat)].name : "default";
        Mesh mesh = builder.finish(name);
        if (mesh.normals.empty()) computeVertexNormals(mesh);
        scene.meshes.push_back(std::move(mesh));
        Shape s;
        s.name = name;
        s.mesh = int(scene.meshes.size() - 1);
        if (mat >= 0) {
            scene.materials.push_back(materials[size_t(mat)]);
            s.material = int(scene.materials.size() - 1);
            s.emission = emission[size_t(mat)];
            s.origin = materials[size_t(mat)].origin;
        } else {
            if (defaultMaterial < 0) {
                scene.materials.push_back(Material{});
                scene.materials.back().name = "default";
                defaultMaterial = int(scene.materials.size() - 1);
            }
            s.material = defaultMaterial;
        }
        scene.shapes.push_back(s);
    }
    if (scene.shapes.empty()) throw UserError(path + ": OBJ file has no faces");
    bool emissive = std::any_of(scene.shapes.begin(), scene.shapes.end(),
                                [](const Shape& s) { return glm::length(s.emission) > 0.0f; });
    if (!emissive) {
        Light env;
        env.type = LightType::Constant;
        scene.lights.push_back(env);
        detail::addWarning(scene, path +
                                      ": no emissive (Ke) materials; added a constant "
                                      "environment light of radiance 1");
    }
    detail::setDefaultCamera(scene);
    return scene;
}

}  // namespace loom::scene
