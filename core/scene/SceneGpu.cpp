#include "core/scene/SceneGpu.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>

#include "core/scene/Bvh.h"
#include "core/scene/Camera.h"
#include "core/scene/EnvMapDistribution.h"
#include "core/scene/MaterialGpu.h"
#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom::scene {

namespace {

// Layouts mirrored from shaders/lib/scene.glsl (std430; every member 16-byte friendly).
struct VertexGpu {
    glm::vec4 positionU;
    glm::vec4 normalV;
};
struct ShapeGpu {
    uint32_t material, flags, lightOffset, firstTriangle;
    glm::vec4 emission;
};
struct TextureGpu {
    uint32_t offset, width, height, kind;
    glm::vec4 color0, color1, uvScale;
};
struct LightGpu {
    uint32_t type, index;
    float pmf;
    uint32_t flags;  // Light::flags (point/spot/directional/environment), shape flags (triangles)
    glm::vec4 p0, p1, p2;
};
struct CameraPoseGpu {
    glm::vec4 origin, target, up, lens;
};
struct SceneInfoGpu {
    CameraPoseGpu open, close, prev, prevClose;  // prev*: the previous frame's shutter open / close
    glm::uvec4 counts;
    glm::vec4 boundsCenter;
    // Where the previous frame's geometry is: vertex base, BVH node base, BVH triangle base
    // (all 0 when it is this frame's: static scenes, or nothing moved).
    glm::uvec4 previousGeometry{0u};
    // Motion blur of moving shapes: offset of the shutter-close vertices, and the BVH motion
    // offsets of this frame's and the previous frame's tree (all 0 without shutter motion).
    glm::uvec4 motion{0u};
};
static_assert(sizeof(VertexGpu) == 32 && sizeof(ShapeGpu) == 32 && sizeof(TextureGpu) == 64 &&
              sizeof(LightGpu) == 64 && sizeof(SceneInfoGpu) == 4 * 64 + 64);

enum : uint32_t {
    kLightTriangle,
    kLightPoint,
    kLightSpot,
    kLightDirectional,
    kLightEnv,
    kLightConstant
};

float luminance(glm::vec3 c) {
    return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
}

template <class T>
std::shared_ptr<gpu::Buffer> upload(gpu::Context& gpu, const std::vector<T>& data,
                                    const std::string& name) {
    auto buf = gpu.createBuffer(std::max<size_t>(data.size() * sizeof(T), 16), name);
    if (!data.empty()) gpu.uploadBuffer(*buf, data.data(), data.size() * sizeof(T));
    return buf;
}

// Scene records in an RGBA32UI image, texel i at (i % kRecordImageWidth, i / kRecordImageWidth)
// (shaders/lib/scene.glsl SCENE_TEXEL): lavapipe loads image texels far cheaper than buffer
// words at divergent addresses (bench/llvmpipe_loads.sh). Records are multiples of 16 bytes.
constexpr uint32_t kRecordImageWidth = 8192, kRecordImageMaxRows = 16384;

uint32_t recordImageRows(size_t bytes) {
    const size_t texels = std::max<size_t>((bytes + 15) / 16, 1);
    return uint32_t((texels + kRecordImageWidth - 1) / kRecordImageWidth);
}

std::shared_ptr<gpu::Image> recordImage(gpu::Context& gpu, const void* data, size_t bytes,
                                        const std::string& name) {
    const uint32_t rows = recordImageRows(bytes);
    if (rows > kRecordImageMaxRows)
        throw UserError(
            fmt::format("scene data '{}' of {} MB exceeds its image ({} rows of {} "
                        "16-byte texels)",
                        name, bytes >> 20, kRecordImageMaxRows, kRecordImageWidth));
    std::vector<glm::uvec4> texels(size_t(rows) * kRecordImageWidth, glm::uvec4(0u));
    if (bytes) std::memcpy(texels.data(), data, bytes);
    auto image = gpu.createImage(kRecordImageWidth, rows, gpu::Format::RGBA32UI, name);
    gpu.uploadImage(*image, texels.data());
    return image;
}

template <class T>
std::shared_ptr<gpu::Image> recordImage(gpu::Context& gpu, const std::vector<T>& data,
                                        const std::string& name) {
    static_assert(sizeof(T) % 16 == 0, "scene records are whole 16-byte texels");
    return recordImage(gpu, data.data(), data.size() * sizeof(T), name);
}

// World-space vertices of `mesh` under `toWorld` (normals by the inverse transpose).
void transformVertices(const Mesh& mesh, const glm::mat4& toWorld, VertexGpu* out,
                       glm::vec3* positions) {
    glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(toWorld)));
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        glm::vec3 p = glm::vec3(toWorld * glm::vec4(mesh.positions[v], 1.0f));
        glm::vec3 n(0.0f);
        if (!mesh.faceNormals && v < mesh.normals.size()) {
            n = normalMatrix * mesh.normals[v];
            float len = glm::length(n);
            n = len > 0.0f ? n / len : glm::vec3(0.0f);
        }
        glm::vec2 uv = v < mesh.uvs.size() ? mesh.uvs[v] : glm::vec2(0.0f);
        out[v] = {glm::vec4(p, uv.x), glm::vec4(n, uv.y)};
        positions[v] = p;
    }
}

// Rows of the affine map from a shape's world position now to the previous frame's
// (prev * now^-1, in double so that a static shape gets the identity exactly).
std::array<glm::vec4, 3> motionRows(const glm::mat4& prev, const glm::mat4& now) {
    glm::dmat4 m = glm::dmat4(prev) * glm::inverse(glm::dmat4(now));
    if (prev == now) m = glm::dmat4(1.0);
    std::array<glm::vec4, 3> rows;
    for (int r = 0; r < 3; ++r) rows[r] = glm::vec4(m[0][r], m[1][r], m[2][r], m[3][r]);
    return rows;
}

// Object to world of `shape` at shutter close of the frame whose shutter closes at `time`:
// its keyframe path there, else its transform_end (Shape::toWorldEnd), else its toWorld.
glm::mat4 shapeToWorldAtClose(const Shape& shape, float time) {
    if (!shape.path.empty() || !shape.moving) return shapeToWorldAt(shape, time);
    return shape.toWorldEnd;
}

}  // namespace

// Shapes with a per-frame path (Shape::path), a deformation (Shape::deformation) or shutter
// motion (Shape::moving): where their vertices live, and the object to world of the current
// and the previous frame time.
struct MovingShape {
    size_t shape;
    uint32_t firstVertex;
    glm::mat4 now, prev;
    bool deforming = false;
};

struct SceneGpu::Impl {
    std::shared_ptr<gpu::Image> vertices, triangles, shapes, materials, textures, texels, lights;
    std::shared_ptr<gpu::Buffer> lightCdf, info, envDistribution;
    // Moving shapes: the vertex image's texels on the CPU, whose changed rows are uploaded.
    std::vector<VertexGpu> vertexTexels;
    BvhGpu bvh;
    SceneInfoGpu infoData{};
    std::vector<EnvMapDistribution> envs;
    // Per shape, 3 rows of the previous-frame map (motionRows); identity for static shapes.
    std::shared_ptr<gpu::Buffer> shapeMotion;
    std::vector<glm::vec4> shapeMotionRows;
    // Dynamic scenes only (empty when nothing moves): CPU copies for re-transforming moving
    // shapes and rebuilding the BVH. Their vertex buffer holds this frame's vertices followed
    // by the previous frame's, and the node image both BVHs (BvhGpu::upload), so that temporal
    // reuse can evaluate paths in the previous frame's geometry (scene_select_frame).
    std::vector<MovingShape> moving;
    BvhBuild lastBuild;
    std::vector<VertexGpu> cpuVertices;
    std::vector<glm::vec3> cpuPositions;
    std::vector<glm::uvec3> cpuIndices;
    std::vector<uint32_t> cpuMasks;
    float shapeTime = 0.0f;  // frame time the vertices are at
    // Motion blur over the shutter (blur: the camera's shutter is open for a while): the
    // vertices at shutter close, as blocks 2 (this frame) and 3 (the previous frame) of the
    // vertex buffer, and the frame time they are at.
    bool blur = false;
    float closeTime = 0.0f;
    std::vector<VertexGpu> cpuCloseVertices;
    std::vector<glm::vec3> cpuClosePositions;
};

SceneGpu::SceneGpu(gpu::Context& gpu, Scene sceneIn)
    : mImpl(std::make_unique<Impl>()), mGpu(gpu), mScene(std::move(sceneIn)) {
    auto t0 = std::chrono::steady_clock::now();
    const Scene& s = mScene;
    const float shapeTime = s.camera.shutterOpen;  // frame 0 at shutter open, as setFrame(0)
    mImpl->shapeTime = shapeTime;

    // Flatten shapes into world-space triangles, contiguous per shape.
    std::vector<VertexGpu> vertices;
    std::vector<glm::uvec4> triangles;
    std::vector<glm::vec3> positions;
    std::vector<glm::uvec3> indices;
    std::vector<uint32_t> masks;
    std::vector<ShapeGpu> shapes;
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (size_t si = 0; si < s.shapes.size(); ++si) {
        const Shape& shape = s.shapes[si];
        if (shape.mesh < 0 || size_t(shape.mesh) >= s.meshes.size())
            throw UserError("scene '" + s.sourceFile + "': shape '" + shape.name + "' has no mesh");
        const Mesh& mesh = s.meshes[shape.mesh];
        ShapeGpu sg{};
        sg.material = shape.material < 0 ? 0u : uint32_t(shape.material);
        sg.flags = shape.flags;
        sg.lightOffset = ~0u;
        sg.firstTriangle = uint32_t(triangles.size());
        sg.emission = glm::vec4(shape.emission, mesh.uvs.empty() ? 0.0f : 1.0f);
        shapes.push_back(sg);
        uint32_t base = uint32_t(vertices.size());
        // Moving shapes start at frame time 0 (setFrame moves them); the bounds cover their
        // keyframes so that light sampling discs (directional, environment) cover them.
        glm::mat4 toWorld = shapeToWorldAt(shape, shapeTime);
        const bool deforming = bool(shape.deformation);
        if (!shape.path.empty() || deforming || shape.moving)
            mImpl->moving.push_back({si, base, toWorld, toWorld, deforming});
        vertices.resize(base + mesh.positions.size());
        positions.resize(base + mesh.positions.size());
        if (deforming) {
            Mesh now = shape.deformation(shapeTime);
            if (now.positions.size() != mesh.positions.size() || now.indices != mesh.indices)
                throw UserError("scene '" + s.sourceFile + "': shape '" + shape.name +
                                "': its deformation changes the mesh topology");
            transformVertices(now, toWorld, vertices.data() + base, positions.data() + base);
        } else {
            transformVertices(mesh, toWorld, vertices.data() + base, positions.data() + base);
        }
        for (size_t v = base; v < positions.size(); ++v) {
            lo = glm::min(lo, positions[v]);
            hi = glm::max(hi, positions[v]);
        }
        if (shape.moving && shape.path.empty()) {  // transform_end: its pose at shutter close
            for (const glm::vec3& p : mesh.positions) {
                glm::vec3 w = glm::vec3(shape.toWorldEnd * glm::vec4(p, 1.0f));
                lo = glm::min(lo, w);
                hi = glm::max(hi, w);
            }
        }
        if (!shape.path.empty()) {
            // Keyframes and segment midpoints, padded for the arcs of rotations in between.
            std::vector<float> times;
            for (size_t k = 0; k < shape.path.size(); ++k) {
                times.push_back(shape.path[k].time);
                if (k + 1 < shape.path.size())
                    for (int i = 1; i < 8; ++i)
                        times.push_back(
                            glm::mix(shape.path[k].time, shape.path[k + 1].time, float(i) / 8.0f));
            }
            glm::vec3 mlo(1e30f), mhi(-1e30f);
            for (float t : times) {
                glm::mat4 m = shapeToWorldAt(shape, t);
                for (const glm::vec3& p : mesh.positions) {
                    glm::vec3 w = glm::vec3(m * glm::vec4(p, 1.0f));
                    mlo = glm::min(mlo, w);
                    mhi = glm::max(mhi, w);
                }
            }
            glm::vec3 pad = 0.05f * (mhi - mlo);
            lo = glm::min(lo, mlo - pad);
            hi = glm::max(hi, mhi + pad);
        }
        if (deforming) {  // its motion is not known ahead: a margin around frame 0's extent
            glm::vec3 slo(1e30f), shi(-1e30f);
            for (size_t v = base; v < positions.size(); ++v) {
                slo = glm::min(slo, positions[v]);
                shi = glm::max(shi, positions[v]);
            }
            glm::vec3 pad(0.1f * glm::length(shi - slo));
            lo = glm::min(lo, slo - pad);
            hi = glm::max(hi, shi + pad);
        }
        for (const auto& tri : mesh.indices) {
            triangles.push_back(glm::uvec4(tri + base, uint32_t(si)));
            indices.push_back(tri + base);
            // BVH mask bits: visibility and caustic flags (low 6 bits) | user mask bits.
            masks.push_back((shape.flags & 0x3fu) | ((shape.rayMask & 0x3u) << 6));
        }
    }
    if (triangles.empty()) throw UserError("scene '" + s.sourceFile + "' has no triangles");
    glm::vec3 center = 0.5f * (lo + hi);
    float radius = 0.5f * glm::length(hi - lo);
    mBounds = glm::vec4(center, radius);

    // Materials (a default diffuse when the scene has none).
    std::vector<MaterialGpu> materials;
    for (const auto& m : s.materials) materials.push_back(packMaterial(m));
    if (materials.empty()) materials.push_back(packMaterial(Material{}));

    // Textures: all texels in one buffer.
    std::vector<TextureGpu> textures;
    std::vector<glm::vec4> texels;
    for (const auto& t : s.textures) {
        TextureGpu tg{};
        tg.offset = uint32_t(texels.size());
        tg.kind = uint32_t(t.kind);
        tg.color0 = glm::vec4(t.color0, 1.0f);
        tg.color1 = glm::vec4(t.color1, 1.0f);
        tg.uvScale = glm::vec4(t.uvScale, 0.0f, 0.0f);
        if (t.kind == TextureKind::Bitmap) {
            tg.width = t.width;
            tg.height = t.height;
            for (size_t i = 0; i + 3 < t.rgba.size(); i += 4)
                texels.emplace_back(t.rgba[i], t.rgba[i + 1], t.rgba[i + 2], t.rgba[i + 3]);
            if (texels.size() - tg.offset != size_t(t.width) * t.height)
                throw UserError("texture '" + t.name + "' has no texel data");
        }
        textures.push_back(tg);
    }
    // Normal maps read as slopes (kMaterialNormalSlopes): a slope copy of each such map, shared
    // by the materials that use it that way (another material may read the same map as normals).
    std::map<uint32_t, uint32_t> slopeCopies;
    for (auto& mg : materials) {
        uint32_t src = mg.textures.z;
        if (!(mg.info.y & kMaterialNormalSlopes) || src >= textures.size()) continue;
        auto [it, fresh] = slopeCopies.try_emplace(src, uint32_t(textures.size()));
        if (fresh) {
            TextureGpu tg = textures[src];
            tg.color0 = normalMapSlopeTexel(tg.color0);
            tg.color1 = normalMapSlopeTexel(tg.color1);
            if (tg.kind == uint32_t(TextureKind::Bitmap)) {
                uint32_t from = tg.offset;
                tg.offset = uint32_t(texels.size());
                for (uint32_t i = 0; i < tg.width * tg.height; ++i)
                    texels.push_back(normalMapSlopeTexel(texels[from + i]));
            }
            textures.push_back(tg);
        }
        mg.textures.z = it->second;
    }

    // Light list: emissive triangles (power = pi * L * area, one-sided), then analytic lights.
    std::vector<LightGpu> lights;
    std::vector<float> power;
    for (size_t si = 0; si < s.shapes.size(); ++si) {
        const Shape& shape = s.shapes[si];
        if (luminance(shape.emission) <= 0.0f) continue;
        shapes[si].lightOffset = uint32_t(lights.size());
        uint32_t first = shapes[si].firstTriangle;
        uint32_t count = uint32_t(s.meshes[shape.mesh].indices.size());
        for (uint32_t t = first; t < first + count; ++t) {
            glm::uvec4 tri = triangles[t];
            float area = 0.5f * glm::length(glm::cross(positions[tri.y] - positions[tri.x],
                                                       positions[tri.z] - positions[tri.x]));
            lights.push_back({kLightTriangle, t, 0.0f, shape.flags, {}, {}, {}});
            power.push_back(float(M_PI) * luminance(shape.emission) * area);
            ++mStats.emissiveTriangles;
        }
    }
    uint32_t envIndex = ~0u;
    for (const auto& l : s.lights) {
        LightGpu lg{};
        lg.flags = l.flags;
        float p = 0.0f;
        float discArea = float(M_PI) * radius * radius;
        switch (l.type) {
            case LightType::Point:
            case LightType::Spot: {
                lg.type = l.type == LightType::Point ? kLightPoint : kLightSpot;
                lg.p0 = glm::vec4(l.position, std::cos(glm::radians(l.beamWidth)));
                lg.p1 = glm::vec4(l.intensity, 0.0f);
                lg.p2 =
                    glm::vec4(glm::normalize(l.direction), std::cos(glm::radians(l.cutoffAngle)));
                p = 4.0f * float(M_PI) * luminance(l.intensity);
                break;
            }
            case LightType::Directional:
                lg.type = kLightDirectional;
                lg.p0 = glm::vec4(-glm::normalize(l.direction), 0.0f);  // towards the light
                lg.p1 = glm::vec4(l.intensity, 0.0f);
                p = luminance(l.intensity) * discArea;
                break;
            case LightType::Constant:
                lg.type = kLightConstant;
                lg.p1 = glm::vec4(l.intensity * l.scale, 0.0f);
                p = float(M_PI) * luminance(l.intensity * l.scale) * discArea;
                break;
            case LightType::Environment: {
                if (l.envTexture < 0 || size_t(l.envTexture) >= s.textures.size())
                    throw UserError("environment light without a texture");
                const Texture& tex = s.textures[l.envTexture];
                lg.type = kLightEnv;
                lg.index = uint32_t(mImpl->envs.size());
                lg.p1 = glm::vec4(l.scale, 0.0f, 0.0f, 0.0f);
                mImpl->envs.push_back(EnvMapDistribution(tex, l.toWorld));
                p = float(M_PI) * l.scale * mImpl->envs.back().averageLuminance() * discArea;
                break;
            }
        }
        if (l.type == LightType::Environment || l.type == LightType::Constant) {
            if (envIndex != ~0u) {
                logWarning("scene '{}': more than one environment light; using the first",
                           s.sourceFile);
                continue;
            }
            envIndex = uint32_t(lights.size());
        }
        lights.push_back(lg);
        power.push_back(std::max(p, 0.0f));
    }
    // Selection pmf proportional to power; inclusive CDF for the binary search.
    double total = 0.0;
    for (float p : power) total += p;
    std::vector<float> cdf(lights.size());
    double acc = 0.0;
    for (size_t i = 0; i < lights.size(); ++i) {
        lights[i].pmf = total > 0 ? float(power[i] / total) : 1.0f / float(lights.size());
        acc += lights[i].pmf;
        cdf[i] = float(acc);
    }
    if (!cdf.empty()) cdf.back() = 1.0f;  // guard the last bin against round-off

    for (const auto& sg : shapes) {
        if (sg.material >= materials.size()) continue;
        const MaterialGpu& m = materials[sg.material];
        mMaterialTypes |= 1u << m.info.x;
        for (int slot = 0; slot < 3; ++slot)
            if (m.textures[slot] != kMaterialNoTexture) mTextureUses |= 1u << slot;
    }
    for (const auto& lg : lights) mLightTypes |= 1u << lg.type;

    auto& g = *mImpl;
    if (g.moving.empty()) {
        g.vertices = recordImage(gpu, vertices, "scene_vertex_texels");
    } else {
        // This frame's and the previous frame's vertices at shutter open, then the same at
        // shutter close (motion blur; copies of the open ones until a frame blurs).
        std::vector<VertexGpu>& blocks = g.vertexTexels;
        blocks.reserve(4 * vertices.size());
        for (int b = 0; b < 4; ++b) blocks.insert(blocks.end(), vertices.begin(), vertices.end());
        g.vertices = recordImage(gpu, blocks, "scene_vertex_texels");
        blocks.resize(size_t(g.vertices->height()) * kRecordImageWidth * 16 / sizeof(VertexGpu));
    }
    g.triangles = recordImage(gpu, triangles, "scene_triangle_texels");
    g.shapes = recordImage(gpu, shapes, "scene_shape_texels");
    g.materials = recordImage(gpu, materials, "scene_material_texels");
    g.textures = recordImage(gpu, textures, "scene_texture_texels");
    g.texels = recordImage(gpu, texels, "scene_texel_texels");
    g.lights = recordImage(gpu, lights, "scene_light_texels");
    g.lightCdf = upload(gpu, cdf, "SceneLightCdf");
    g.info = gpu.createBuffer(sizeof(SceneInfoGpu), "SceneInfoBuffer");
    g.infoData.counts = glm::uvec4(triangles.size(), shapes.size(), lights.size(), envIndex);
    g.infoData.boundsCenter = mBounds;
    g.envDistribution = packEnvMaps(gpu, g.envs);

    BvhBuild build = buildBvh(positions, indices, masks);
    g.bvh.upload(gpu, build);
    if (!g.moving.empty()) g.lastBuild = build;

    g.shapeMotionRows.resize(shapes.size() * 3);
    for (size_t si = 0; si < shapes.size(); ++si) {
        auto rows = motionRows(glm::mat4(1.0f), glm::mat4(1.0f));
        std::copy(rows.begin(), rows.end(), g.shapeMotionRows.begin() + long(3 * si));
    }
    g.shapeMotion = upload(gpu, g.shapeMotionRows, "SceneShapeMotion");
    if (!g.moving.empty()) {  // keep what per-frame updates need
        g.cpuCloseVertices = vertices;
        g.cpuClosePositions = positions;
        g.cpuVertices = std::move(vertices);
        g.cpuPositions = std::move(positions);
        g.cpuIndices = std::move(indices);
        g.cpuMasks = std::move(masks);
    }

    mStats.triangles = triangles.size();
    mStats.shapes = shapes.size();
    mStats.materials = materials.size();
    mStats.textures = textures.size();
    mStats.lights = lights.size();
    mStats.bvhNodes = build.stats.nodes;
    mStats.buildMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    logInfo(
        "scene: {} triangles, {} shapes, {} lights ({} emissive triangles), BVH {} nodes, "
        "{:.0f} ms",
        mStats.triangles, mStats.shapes, mStats.lights, mStats.emissiveTriangles, mStats.bvhNodes,
        mStats.buildMs);
}

SceneGpu::~SceneGpu() = default;

void SceneGpu::bind(gpu::Bindings& b) const {
    auto& g = *mImpl;
    b.set("scene_vertex_texels", g.vertices)
        .set("scene_triangle_texels", g.triangles)
        .set("scene_shape_texels", g.shapes)
        .set("scene_material_texels", g.materials)
        .set("scene_texture_texels", g.textures)
        .set("scene_texel_texels", g.texels)
        .set("scene_light_texels", g.lights)
        .set("SceneLightCdf", g.lightCdf)
        .set("SceneInfoBuffer", g.info)
        .set("SceneShapeMotion", g.shapeMotion);
    bindEnvMaps(b, g.envDistribution);
    g.bvh.bind(b);
}

bool SceneGpu::shapesMoveOverShutter() const {
    return !mImpl->moving.empty() && mScene.camera.shutterClose > mScene.camera.shutterOpen;
}

bool SceneGpu::thinLens() const {
    const auto& i = mImpl->infoData;
    return i.open.up.w > 0.0f || i.close.up.w > 0.0f || i.prev.up.w > 0.0f ||
           i.prevClose.up.w > 0.0f;
}

void SceneGpu::setCamera(const Camera& camera) {
    mScene.camera = camera;
    mCameraDirty = true;
    ++mRevision;
}

namespace {
CameraPoseGpu poseAt(const Camera& base, float time, uint32_t width, uint32_t height) {
    Camera c = cameraAt(base, time);
    glm::vec3 origin = glm::vec3(c.toWorld * glm::vec4(0, 0, 0, 1));
    glm::vec3 forward = glm::normalize(glm::vec3(c.toWorld * glm::vec4(0, 0, 1, 0)));
    glm::vec3 up = glm::normalize(glm::vec3(c.toWorld * glm::vec4(0, 1, 0, 0)));
    float aspect = float(width) / float(height);
    float t = std::tan(glm::radians(c.fov) * 0.5f);
    float tx, ty;
    using Axis = Camera::FovAxis;
    bool xAxis = c.fovAxis == Axis::X || (c.fovAxis == Axis::Smaller && width <= height) ||
                 (c.fovAxis == Axis::Larger && width >= height);
    if (xAxis) {
        tx = t;
        ty = t / aspect;
    } else {
        ty = t;
        tx = t * aspect;
    }
    CameraPoseGpu p;
    p.origin = glm::vec4(origin, tx);
    p.target = glm::vec4(origin + forward, ty);
    p.up = glm::vec4(up, c.type == CameraType::ThinLens ? c.apertureRadius : 0.0f);
    p.lens = glm::vec4(c.focusDistance, c.shutterClose - c.shutterOpen, float(c.type), 0.0f);
    return p;
}
}  // namespace

void SceneGpu::updateShapes(float frameTime, bool firstFrame) {
    auto& g = *mImpl;
    const auto start = std::chrono::steady_clock::now();
    if (g.moving.empty()) return;  // static scene: nothing to do, ever
    const Camera& cam = mScene.camera;
    const float time = frameTime + cam.shutterOpen, closeTime = frameTime + cam.shutterClose;
    const bool blur = cam.shutterClose > cam.shutterOpen;
    std::vector<glm::mat4> now(g.moving.size());
    bool moved = false;
    for (size_t i = 0; i < g.moving.size(); ++i) {
        now[i] = shapeToWorldAt(mScene.shapes[g.moving[i].shape], time);
        moved =
            moved || now[i] != g.moving[i].now || (g.moving[i].deforming && time != g.shapeTime);
    }
    const bool closeChanged = blur != g.blur || (blur && closeTime != g.closeTime);
    g.shapeTime = time;
    if (!moved && !closeChanged) {  // nothing moved since the last frame: it is also the previous
        settleShapes();
        return;
    }
    // The previous frame's vertices stay behind this frame's (block 1, and block 3 at shutter
    // close): only moving shapes differ there.
    const size_t vertexCount = g.cpuVertices.size();
    auto uploadRange = [&](const std::vector<VertexGpu>& from, const MovingShape& m, size_t count,
                           size_t block) {
        if (count == 0) return;
        const size_t first = block * vertexCount + m.firstVertex;
        std::copy_n(from.begin() + long(m.firstVertex), count,
                    g.vertexTexels.begin() + long(first));
        constexpr size_t kPerRow = kRecordImageWidth * 16 / sizeof(VertexGpu);
        const size_t row0 = first / kPerRow, row1 = (first + count - 1) / kPerRow;
        mGpu.uploadImageRows(*g.vertices, g.vertexTexels.data() + row0 * kPerRow, uint32_t(row0),
                             uint32_t(row1 - row0 + 1));
    };
    for (size_t i = 0; i < g.moving.size(); ++i) {
        MovingShape& m = g.moving[i];
        const Shape& shape = mScene.shapes[m.shape];
        const Mesh& mesh = mScene.meshes[shape.mesh];
        const size_t count = mesh.positions.size();
        if (moved) {
            uploadRange(g.cpuVertices, m, count, 1);
            uploadRange(g.cpuCloseVertices, m, count, 3);
            m.prev = firstFrame ? now[i] : m.now;
        } else {
            m.prev = now[i];
        }
        // Re-tessellated at this time; the motion map stays the rigid part (a deforming
        // surface has no affine previous-frame map).
        auto place = [&](float t, const glm::mat4& toWorld, std::vector<VertexGpu>& vertices,
                         std::vector<glm::vec3>& positions) {
            if (m.deforming) {
                Mesh deformed = shape.deformation(t);
                if (deformed.positions.size() != count)
                    throw UserError("shape '" + shape.name +
                                    "': its deformation changes the vertex count");
                transformVertices(deformed, toWorld, vertices.data() + m.firstVertex,
                                  positions.data() + m.firstVertex);
            } else {
                transformVertices(mesh, toWorld, vertices.data() + m.firstVertex,
                                  positions.data() + m.firstVertex);
            }
        };
        if (m.deforming || now[i] != m.now) {
            place(time, now[i], g.cpuVertices, g.cpuPositions);
            uploadRange(g.cpuVertices, m, count, 0);
        }
        if (blur) {
            place(closeTime, shapeToWorldAtClose(shape, closeTime), g.cpuCloseVertices,
                  g.cpuClosePositions);
        } else {  // no blur: shutter close is shutter open
            std::copy_n(g.cpuVertices.begin() + m.firstVertex, count,
                        g.cpuCloseVertices.begin() + m.firstVertex);
            std::copy_n(g.cpuPositions.begin() + m.firstVertex, count,
                        g.cpuClosePositions.begin() + m.firstVertex);
        }
        uploadRange(g.cpuCloseVertices, m, count, 2);
        m.now = now[i];
    }
    g.blur = blur;
    g.closeTime = closeTime;
    uploadMotionRows();
    // Rigid motion changes the tree's boxes: rebuild it (milliseconds for the project scenes;
    // a two-level BVH would spare the static part of large scenes), the last tree behind it.
    // Under motion blur the boxes bound both ends of the shutter (buildMotionBvh).
    BvhBuild build =
        blur ? buildMotionBvh(g.cpuPositions, g.cpuClosePositions, g.cpuIndices, g.cpuMasks)
             : buildBvh(g.cpuPositions, g.cpuIndices, g.cpuMasks);
    g.bvh.upload(mGpu, build, &g.lastBuild);
    g.infoData.previousGeometry = firstFrame || !moved
                                      ? glm::uvec4(0u)
                                      : glm::uvec4(uint32_t(vertexCount), g.bvh.previousNodeBase,
                                                   g.bvh.previousTriangleBase, 0u);
    g.infoData.motion = blur ? glm::uvec4(uint32_t(2 * vertexCount), g.bvh.motionOffset,
                                          g.bvh.previousMotionOffset, 0u)
                             : glm::uvec4(0u);
    g.lastBuild = std::move(build);
    mStats.bvhNodes = g.lastBuild.stats.nodes;
    mStats.bvhBuildMs = g.lastBuild.stats.buildMs;
    mStats.adjacencyMs = g.lastBuild.stats.adjacencyMs;
    mStats.updateMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void SceneGpu::uploadMotionRows() {
    auto& g = *mImpl;
    for (const MovingShape& m : g.moving) {
        auto rows = motionRows(m.prev, m.now);
        std::copy(rows.begin(), rows.end(), g.shapeMotionRows.begin() + long(3 * m.shape));
    }
    if (!g.moving.empty())
        mGpu.uploadBuffer(*g.shapeMotion, g.shapeMotionRows.data(),
                          g.shapeMotionRows.size() * sizeof(glm::vec4));
}

void SceneGpu::settleShapes() {
    auto& g = *mImpl;
    for (MovingShape& m : g.moving) m.prev = m.now;
    uploadMotionRows();
    g.infoData.previousGeometry = glm::uvec4(0u);
}

void SceneGpu::setFrame(float time, uint32_t width, uint32_t height) {
    auto& info = mImpl->infoData;
    if (!mCameraDirty && time == mTime && width == mWidth && height == mHeight) {
        // The same frame again: the previous frame is now this one (no motion; history made in
        // this geometry).
        if (mPreviousDiffers) {
            info.prev = info.open;
            info.prevClose = info.close;
            settleShapes();
            mGpu.uploadBuffer(*mImpl->info, &info, sizeof(info));
            mPreviousDiffers = false;
        }
        return;
    }
    mPreviousDiffers = true;
    const Camera& c = mScene.camera;
    CameraPoseGpu prev = info.open, prevClose = info.close;
    info.open = poseAt(c, time + c.shutterOpen, width, height);
    info.close = poseAt(c, time + c.shutterClose, width, height);
    // Previous frame's poses: the last uploaded ones (this frame's on the first frame).
    bool first = mTime < 0.0f || width != mWidth || height != mHeight;
    info.prev = first ? info.open : prev;
    info.prevClose = first ? info.close : prevClose;
    // Shapes move with the frame time, and over the shutter when it changes length.
    const bool shutterChanged = c.shutterOpen != mShutterOpen || c.shutterClose != mShutterClose;
    if (time != mTime || shutterChanged) updateShapes(time, mTime < 0.0f);
    mShutterOpen = c.shutterOpen;
    mShutterClose = c.shutterClose;
    mGpu.uploadBuffer(*mImpl->info, &info, sizeof(info));
    if (time != mTime || mCameraDirty) ++mRevision;
    mTime = time;
    mWidth = width;
    mHeight = height;
    mCameraDirty = false;
}

}  // namespace loom::scene
