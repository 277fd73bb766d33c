#include "passes/partitioned_sms/ManifoldPairs.h"

#include <cstring>
#include <glm/glm.hpp>
#include <vector>

#include "core/graph/RenderGraph.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneGpu.h"

namespace loom {

namespace {

uint32_t floatBits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}

// Ritter's bounding sphere: within a few percent of the smallest, enough for a seed cone.
glm::vec4 boundingSphere(const std::vector<glm::vec3>& p) {
    glm::vec3 a = p[0], b = a;
    for (auto& q : p)
        if (glm::length(q - a) > glm::length(b - a)) b = q;
    glm::vec3 c = b;
    for (auto& q : p)
        if (glm::length(q - b) > glm::length(c - b)) c = q;
    glm::vec3 centre = 0.5f * (b + c);
    float r = 0.5f * glm::length(c - b);
    for (auto& q : p) {
        float d = glm::length(q - centre);
        if (d > r) {
            float nr = 0.5f * (r + d);
            centre += (d - nr) / d * (q - centre);
            r = nr;
        }
    }
    return {centre, r * 1.0001f + 1e-6f};
}

}  // namespace

bool ManifoldPairs::roughCasters(const scene::Scene& s) {
    for (const auto& shape : s.shapes) {
        if (!(shape.flags & (scene::kCausticCasterReflect | scene::kCausticCasterRefract)))
            continue;
        auto type = s.materials[shape.material].type;
        if (type == scene::BsdfType::RoughConductor || type == scene::BsdfType::RoughDielectric)
            return true;
    }
    return false;
}

void ManifoldPairs::build(ExecuteContext& ctx, const std::string& pass) {
    const scene::SceneGpu& gpuScene = ctx.scene();
    const scene::Scene& s = gpuScene.cpu();
    if (mScene == &s && mCasterObjects) return;
    // Per emitter object: x first entry, y entries, z area (float bits; 0 = delta light),
    // w shape (area emitters: entries hold triangle indices local to the shape, whose light
    // list offset the GPU has) or ~0u (entries hold light indices). Entries: (index, cdf).
    std::vector<glm::uvec4> emitters;
    std::vector<glm::uvec2> entries;
    std::vector<glm::vec4> casters;  // (bounding sphere), then (shape, 0, 0, 0) as bits
    bool receivers = false;
    for (uint32_t si = 0; si < s.shapes.size(); ++si) {
        const auto& shape = s.shapes[si];
        const auto& mesh = s.meshes[shape.mesh];
        glm::mat4 m = scene::shapeToWorldAt(shape, 0.0f);
        std::vector<glm::vec3> world;
        std::vector<double> areas;
        for (auto i : mesh.indices) {
            glm::vec3 a = glm::vec3(m * glm::vec4(mesh.positions[i.x], 1.0f));
            glm::vec3 b = glm::vec3(m * glm::vec4(mesh.positions[i.y], 1.0f));
            glm::vec3 c = glm::vec3(m * glm::vec4(mesh.positions[i.z], 1.0f));
            world.insert(world.end(), {a, b, c});
            areas.push_back(0.5 * glm::length(glm::cross(b - a, c - a)));
        }
        if (shape.flags & scene::kCausticReceiver) receivers = true;
        if ((shape.flags & (scene::kCausticCasterReflect | scene::kCausticCasterRefract)) &&
            !world.empty()) {
            casters.push_back(boundingSphere(world));
            casters.push_back(glm::vec4(glm::uintBitsToFloat(si), 0, 0, 0));
        }
        if ((shape.flags & scene::kCausticEmitter) && glm::length(shape.emission) > 0) {
            double total = 0;
            for (double a : areas) total += a;
            if (!(total > 0)) continue;
            uint32_t first = uint32_t(entries.size());
            double acc = 0;
            for (uint32_t t = 0; t < areas.size(); ++t) {
                acc += areas[t];
                if (areas[t] > 0) entries.push_back({t, floatBits(float(acc / total))});
            }
            entries.back().y = floatBits(1.0f);
            emitters.push_back(
                {first, uint32_t(entries.size()) - first, floatBits(float(total)), si});
        }
    }
    // Analytic lights follow the emissive triangles in the GPU light list (SceneGpu), one
    // environment at most.
    uint32_t index = uint32_t(gpuScene.stats().emissiveTriangles);
    bool env = false;
    for (const auto& l : s.lights) {
        bool isEnv =
            l.type == scene::LightType::Environment || l.type == scene::LightType::Constant;
        if (isEnv && env) continue;
        env = env || isEnv;
        if (!isEnv && (l.flags & scene::kCausticEmitter)) {
            emitters.push_back({uint32_t(entries.size()), 1u, 0u, ~0u});
            entries.push_back({index, floatBits(1.0f)});
        }
        ++index;
    }
    const std::string where = "pass '" + pass + "', scene '" + s.sourceFile + "'";
    if (casters.empty())
        throw UserError(where + ": no caustic casters (tag specular shapes caustic_caster)");
    if (!receivers)
        throw UserError(where + ": casters but no caustic receivers (tag caustic_receiver)");
    if (emitters.empty())
        throw UserError(where + ": no caustic emitters (tag a light caustic_emitter)");
    auto upload = [&](const void* data, size_t bytes, const char* name) {
        auto buf = ctx.gpu().createBuffer(bytes, name);
        ctx.gpu().uploadBuffer(*buf, data, bytes);
        return buf;
    };
    mEmitterLights = upload(entries.data(), entries.size() * 8, "ManifoldEmitterLights");
    mEmitterObjects = upload(emitters.data(), emitters.size() * 16, "ManifoldEmitterObjects");
    mCasterObjects = upload(casters.data(), casters.size() * 16, "ManifoldCasterObjects");
    mEmitters = uint32_t(emitters.size());
    mCasters = uint32_t(casters.size() / 2);
    mScene = &s;
}

void ManifoldPairs::bind(gpu::Bindings& b) const {
    b.set("ManifoldEmitterLights", mEmitterLights)
        .set("ManifoldEmitterObjects", mEmitterObjects)
        .set("ManifoldCasterObjects", mCasterObjects);
}

}  // namespace loom
