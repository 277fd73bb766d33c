// BVH: GLSL traversal (shaders/lib/bvh.glsl through tests/data/bvh_trace.comp on lavapipe)
// against Embree rtcIntersect1 / rtcOccluded1 on the same rays, plus triangle adjacency.
#include <embree3/rtcore.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>

#include "core/gpu/Context.h"
#include "core/scene/Bvh.h"
#include "core/shader/ShaderCompiler.h"

namespace {

using namespace loom;
using scene::BvhBuild;

struct TriMesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::uvec3> indices;
    std::vector<uint32_t> masks;

    void append(const TriMesh& m, uint32_t mask) {
        const uint32_t base = uint32_t(positions.size());
        positions.insert(positions.end(), m.positions.begin(), m.positions.end());
        for (glm::uvec3 t : m.indices) indices.push_back(t + base);
        masks.insert(masks.end(), m.indices.size(), mask);
    }
};

TriMesh makeSphere(uint32_t rings, uint32_t segments, glm::vec3 center, float radius) {
    TriMesh m;
    for (uint32_t r = 0; r <= rings; ++r) {
        const float theta = float(M_PI) * float(r) / float(rings);
        for (uint32_t s = 0; s < segments; ++s) {
            const float phi = 2.0f * float(M_PI) * float(s) / float(segments);
            m.positions.push_back(center + radius * glm::vec3(std::sin(theta) * std::cos(phi),
                                                              std::cos(theta),
                                                              std::sin(theta) * std::sin(phi)));
        }
    }
    for (uint32_t r = 0; r < rings; ++r) {
        for (uint32_t s = 0; s < segments; ++s) {
            const uint32_t a = r * segments + s, b = r * segments + (s + 1) % segments;
            const uint32_t c = a + segments, d = b + segments;
            if (r > 0) m.indices.push_back({a, b, c});  // skip degenerate pole fans
            if (r + 1 < rings) m.indices.push_back({b, d, c});
        }
    }
    return m;
}

TriMesh makeSoup(uint32_t count, uint32_t seed) {
    TriMesh m;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), size(0.01f, 0.3f);
    for (uint32_t i = 0; i < count; ++i) {
        const glm::vec3 c(u(rng), u(rng), u(rng));
        const float s = size(rng);
        const uint32_t base = uint32_t(m.positions.size());
        for (int k = 0; k < 3; ++k)
            m.positions.push_back(c + s * glm::vec3(u(rng), u(rng), u(rng)));
        m.indices.push_back({base, base + 1, base + 2});
    }
    return m;
}

// Heightfield over [-1,1]^2; the left half is exactly flat (y = 0) to stress flat boxes.
TriMesh makeHeightfield(uint32_t n) {
    TriMesh m;
    for (uint32_t j = 0; j <= n; ++j) {
        for (uint32_t i = 0; i <= n; ++i) {
            const float x = -1.0f + 2.0f * float(i) / float(n),
                        z = -1.0f + 2.0f * float(j) / float(n);
            const float y = x < 0.0f ? 0.0f : 0.2f * std::sin(6.0f * x) * std::cos(5.0f * z);
            m.positions.push_back({x, y, z});
        }
    }
    for (uint32_t j = 0; j < n; ++j) {
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            m.indices.push_back({a, c, b});
            m.indices.push_back({b, c, d});
        }
    }
    return m;
}

// Long slivers (aspect ratio ~1e-3) in random orientations.
TriMesh makeThin(uint32_t count, uint32_t seed) {
    TriMesh m;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (uint32_t i = 0; i < count; ++i) {
        const glm::vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
        const glm::vec3 side = glm::normalize(glm::vec3(u(rng), u(rng), u(rng))) * 1e-3f;
        const uint32_t base = uint32_t(m.positions.size());
        m.positions.insert(m.positions.end(), {a, b, glm::mix(a, b, 0.5f) + side});
        m.indices.push_back({base, base + 1, base + 2});
    }
    return m;
}

struct Ray {
    glm::vec4 o;  // origin, tmin
    glm::vec4 d;  // direction, tmax
};

// Half the rays start outside the bounds aiming inside, half start inside in any direction;
// a quarter of them get a finite tmax.
std::vector<Ray> makeRays(const TriMesh& mesh, uint32_t count, uint32_t seed) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (auto& p : mesh.positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const glm::vec3 c = 0.5f * (lo + hi);
    const float r = glm::length(hi - lo);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    auto unitVector = [&] {
        const float z = 2.0f * u(rng) - 1.0f, phi = 2.0f * float(M_PI) * u(rng);
        const float s = std::sqrt(std::max(0.0f, 1.0f - z * z));
        return glm::vec3(s * std::cos(phi), s * std::sin(phi), z);
    };
    auto inside = [&] { return lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng)); };
    std::vector<Ray> rays(count);
    for (uint32_t i = 0; i < count; ++i) {
        glm::vec3 o, d;
        if (i % 2 == 0) {
            o = c + 1.5f * r * unitVector();
            d = glm::normalize(inside() - o);
        } else {
            o = inside();
            d = unitVector();
        }
        if (i % 16 == 1) d.x = 0.0f;  // axis-parallel components
        if (i % 32 == 3) d = glm::vec3(0.0f, -1.0f, 0.0f);
        const float tmax =
            (i % 4 == 3) ? u(rng) * 2.0f * r : std::numeric_limits<float>::infinity();
        rays[i] = {glm::vec4(o, 0.0f), glm::vec4(d, tmax)};
    }
    return rays;
}

// Double-precision ray/plane intersection with barycentrics (no inside test): the answer
// both float tracers approximate.
struct ExactHit {
    double t = 0.0, u = -1.0, v = -1.0;
    double kappa = 1.0;  // |e1| |e2| / |e1 x e2|: 1 / sine of the angle at v0
    double edgeDistance() const { return std::min({u, v, 1.0 - u - v}); }
};

ExactHit exactIntersect(const TriMesh& m, uint32_t prim, const Ray& r) {
    const glm::uvec3 tri = m.indices[prim];
    const glm::dvec3 v0(m.positions[tri.x]), v1(m.positions[tri.y]), v2(m.positions[tri.z]);
    const glm::dvec3 o(r.o), d(r.d), e1 = v1 - v0, e2 = v2 - v0;
    const glm::dvec3 p = glm::cross(d, e2), s = o - v0, q = glm::cross(s, e1);
    const double det = glm::dot(e1, p);
    if (det == 0.0) return {};
    return {glm::dot(e2, q) / det, glm::dot(s, p) / det, glm::dot(d, q) / det,
            glm::length(e1) * glm::length(e2) / glm::length(glm::cross(e1, e2))};
}

// Embree reference over the triangles whose mask matches rayMask; ids map back to the input.
class EmbreeScene {
public:
    EmbreeScene(RTCDevice device, const TriMesh& mesh, uint32_t rayMask) {
        mScene = rtcNewScene(device);
        rtcSetSceneBuildQuality(mScene, RTC_BUILD_QUALITY_HIGH);
        for (uint32_t t = 0; t < mesh.indices.size(); ++t)
            if (mesh.masks[t] & rayMask) mPrims.push_back(t);
        if (!mPrims.empty()) {
            RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
                geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, mesh.positions.size()));
            std::memcpy(v, mesh.positions.data(), mesh.positions.size() * 12);
            auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
                geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, mPrims.size()));
            for (size_t i = 0; i < mPrims.size(); ++i)
                std::memcpy(idx + 3 * i, &mesh.indices[mPrims[i]], 12);
            rtcCommitGeometry(geom);
            rtcAttachGeometry(mScene, geom);
            rtcReleaseGeometry(geom);
        }
        rtcCommitScene(mScene);
    }
    ~EmbreeScene() { rtcReleaseScene(mScene); }

    RTCRayHit intersect(const Ray& r) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh{};
        setRay(rh.ray, r);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(mScene, &ctx, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) rh.hit.primID = mPrims[rh.hit.primID];
        return rh;
    }
    bool occluded(const Ray& r) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRay ray{};
        setRay(ray, r);
        rtcOccluded1(mScene, &ctx, &ray);
        return ray.tfar == -std::numeric_limits<float>::infinity();
    }

private:
    static void setRay(RTCRay& ray, const Ray& r) {
        ray.org_x = r.o.x, ray.org_y = r.o.y, ray.org_z = r.o.z, ray.tnear = r.o.w;
        ray.dir_x = r.d.x, ray.dir_y = r.d.y, ray.dir_z = r.d.z, ray.tfar = r.d.w;
        ray.mask = 0xffffffffu;
    }
    RTCScene mScene = nullptr;
    std::vector<uint32_t> mPrims;
};

class BvhGpuTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        sGpu = gpu::Context::create();
        sCompiler = new ShaderCompiler({LOOM_SOURCE_DIR "/shaders", LOOM_SOURCE_DIR}, "");
        auto shader = sCompiler->compile("tests/data/bvh_trace.comp");
        sPipeline = sGpu->createPipeline(shader->spirv, shader->reflection, "bvh_trace");
        auto motion =
            sCompiler->compile("tests/data/bvh_trace.comp", {{"LOOM_SHAPE_MOTION_BLUR", "1"}});
        sMotionPipeline = sGpu->createPipeline(motion->spirv, motion->reflection, "bvh_motion");
        sDevice = rtcNewDevice(nullptr);
    }
    static void TearDownTestSuite() {
        sPipeline.reset();
        sMotionPipeline.reset();
        delete sCompiler;
        sGpu.reset();
        rtcReleaseDevice(sDevice);
    }

    // Results (t, prim, u, v) or (occluded, 0, 0, 0) per ray.
    static std::vector<glm::uvec4> trace(const scene::BvhGpu& bvh, const std::vector<Ray>& rays,
                                         uint32_t mask, bool anyHit) {
        return trace(bvh, rays, mask, anyHit, *sPipeline);
    }
    static std::vector<glm::uvec4> trace(const scene::BvhGpu& bvh, const std::vector<Ray>& rays,
                                         uint32_t mask, bool anyHit,
                                         const gpu::ComputePipeline& pipeline, float time = 0.0f) {
        auto rayBuf = sGpu->createBuffer(rays.size() * sizeof(Ray), "rays");
        sGpu->uploadBuffer(*rayBuf, rays.data(), rays.size() * sizeof(Ray));
        auto out = sGpu->createBuffer(rays.size() * sizeof(glm::uvec4), "results");
        gpu::Bindings b;
        bvh.bind(b);
        b.set("rays", rayBuf).set("results", out);
        gpu::PushConstants pc(pipeline);
        pc.set("rayCount", uint32_t(rays.size())).set("mask", mask).set("anyHit", uint32_t(anyHit));
        pc.set("time", time).set("motionOffset", bvh.motionOffset);
        auto cmd = sGpu->beginCommands();
        cmd->dispatchThreads(pipeline, b, &pc, uint32_t(rays.size()));
        sGpu->submit(*cmd);
        std::vector<glm::uvec4> results(rays.size());
        sGpu->downloadBuffer(*out, results.data(), results.size() * sizeof(glm::uvec4));
        return results;
    }

    // Compares GLSL with Embree for every ray; returns the number of edge-ambiguous rays
    // (the two disagree only where a ray passes within float rounding of an edge).
    // With `close` (the same mesh at shutter close), a motion tree traced at shutter fraction
    // `time` is compared with Embree on the mesh interpolated to that time.
    static void compare(const TriMesh& open, const std::vector<Ray>& rays, uint32_t mask,
                        const char* what, const TriMesh* close = nullptr, float time = 0.0f) {
        SCOPED_TRACE(::testing::Message() << what << ", mask 0x" << std::hex << mask);
        TriMesh mesh = open;
        if (close)
            for (size_t i = 0; i < mesh.positions.size(); ++i)
                mesh.positions[i] += time * (close->positions[i] - open.positions[i]);
        const BvhBuild build = close ? scene::buildMotionBvh(open.positions, close->positions,
                                                             open.indices, open.masks)
                                     : scene::buildBvh(open.positions, open.indices, open.masks);
        EXPECT_LE(build.stats.depth, scene::kBvhMaxDepth);
        scene::BvhGpu bvh;
        bvh.upload(*sGpu, build);
        const EmbreeScene ref(sDevice, mesh, mask);
        const gpu::ComputePipeline& pipeline = close ? *sMotionPipeline : *sPipeline;
        const auto closest = trace(bvh, rays, mask, false, pipeline, time);
        const auto any = trace(bvh, rays, mask, true, pipeline, time);

        // t within 1e-4 relative. Below 1% of the scene size the bound is absolute, since both
        // tracers lose digits to v0 - origin when the origin is that close to a surface; and it
        // grows with the triangle's conditioning kappa = |e1||e2| / |e1 x e2| (>= 1), since
        // float edges of a sliver give a plane normal with error ~ kappa ulp (measured: both
        // tracers stay below 1e-5 * kappa against the exact intersection).
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (auto& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
        const double tFloor = 1e-2 * glm::length(hi - lo);
        auto tClose = [&](double a, double b, double kappa = 1.0) {
            return std::abs(a - b) <= 1e-4 * std::max(kappa, 1.0) * std::max(std::abs(b), tFloor);
        };
        uint32_t hits = 0, ties = 0, ambiguous = 0, failures = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            const Ray& ray = rays[i];
            const RTCRayHit e = ref.intersect(ray);
            const bool eHit = e.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            const bool gHit = closest[i].y != 0xffffffffu;
            const uint32_t gPrim = closest[i].y;
            float gt, gu, gv;
            std::memcpy(&gt, &closest[i].x, 4);
            std::memcpy(&gu, &closest[i].z, 4);
            std::memcpy(&gv, &closest[i].w, 4);
            hits += eHit;
            const ExactHit eExact = eHit ? exactIntersect(mesh, e.hit.primID, ray) : ExactHit{};
            const ExactHit gExact = gHit ? exactIntersect(mesh, gPrim, ray) : ExactHit{};
            // A hit within rounding of an edge (scaled by kappa: bary error of a sliver) or of
            // tmin/tmax may go either way.
            auto borderline = [&](const ExactHit& h) {
                return h.edgeDistance() < 1e-4 * h.kappa || tClose(h.t, ray.d.w) ||
                       tClose(h.t, ray.o.w);
            };
            bool ok = true;
            if (eHit && gHit && e.hit.primID == gPrim) {
                // Same triangle: t and (u, v) agree with Embree or, for ill-conditioned slivers
                // where Embree's own float error is larger, with the exact intersection.
                const double k = gExact.kappa;
                ok = tClose(gt, e.ray.tfar, k) && std::abs(gu - e.hit.u) < 1e-3 * k &&
                     std::abs(gv - e.hit.v) < 1e-3 * k;
            } else if (eHit && gHit) {
                // Another triangle at the same distance (shared edge, intersecting triangles),
                // or the nearer of the two hits is borderline and only one tracer took it.
                ok = gExact.edgeDistance() > -1e-4 * gExact.kappa &&
                     tClose(gExact.t, e.ray.tfar, gExact.kappa);
                ties += ok;
                if (!ok) {
                    ok = gt < e.ray.tfar ? borderline(gExact) : borderline(eExact);
                    ambiguous += ok;
                }
            } else if (eHit != gHit) {
                ok = borderline(eHit ? eExact : gExact);
                ambiguous += ok;
            }
            if (gHit) {
                EXPECT_NE(mesh.masks[gPrim] & mask, 0u) << "ray " << i << " hit a masked triangle";
            }
            const bool eOcc = ref.occluded(ray);
            if (bool(any[i].x) != eOcc && !(eHit && borderline(eExact)) &&
                !(gHit && borderline(gExact))) {
                ok = false;
                ADD_FAILURE() << "ray " << i << ": any hit " << any[i].x << ", Embree " << eOcc;
            }
            if (!ok && ++failures <= 10) {
                ADD_FAILURE() << "ray " << i << " o=(" << ray.o.x << "," << ray.o.y << ","
                              << ray.o.z << ") d=(" << ray.d.x << "," << ray.d.y << "," << ray.d.z
                              << ") tmax=" << ray.d.w << ": Embree "
                              << (eHit ? int64_t(e.hit.primID) : -1) << " t=" << e.ray.tfar
                              << " uv=" << e.hit.u << "," << e.hit.v << "; GLSL "
                              << (gHit ? int64_t(gPrim) : -1) << " t=" << gt << " uv=" << gu << ","
                              << gv << "; exact t=" << gExact.t << " uv=" << gExact.u << ","
                              << gExact.v;
            }
        }
        EXPECT_EQ(failures, 0u);
        // Ties and borderline hits are rounding-level events: a handful in 1e5 rays at most.
        EXPECT_LE(ties + ambiguous, rays.size() / 2000 + 2);
        if (mask == 0xffu) {
            EXPECT_GT(hits, rays.size() / 20);  // the rays really exercise the tree
        }
        std::printf(
            "[ %s mask 0x%x ] %zu tris, %u nodes, %u refs, depth %u: %u/%zu hits, %u "
            "ties, %u borderline\n",
            what, mask, mesh.indices.size(), build.stats.nodes, build.stats.triangleRefs,
            build.stats.depth, hits, rays.size(), ties, ambiguous);
    }

    static std::shared_ptr<gpu::Context> sGpu;
    static ShaderCompiler* sCompiler;
    static std::shared_ptr<gpu::ComputePipeline> sPipeline, sMotionPipeline;
    static RTCDevice sDevice;
};

std::shared_ptr<gpu::Context> BvhGpuTest::sGpu;
ShaderCompiler* BvhGpuTest::sCompiler = nullptr;
std::shared_ptr<gpu::ComputePipeline> BvhGpuTest::sPipeline, BvhGpuTest::sMotionPipeline;
RTCDevice BvhGpuTest::sDevice = nullptr;

constexpr uint32_t kRays = 100000;

TriMesh single(const TriMesh& m) {
    TriMesh out;
    out.append(m, 0xffu);
    return out;
}

TEST_F(BvhGpuTest, SphereMatchesEmbree) {
    const TriMesh m = single(makeSphere(96, 128, glm::vec3(0.0f), 1.0f));
    compare(m, makeRays(m, kRays, 1), 0xffu, "sphere");
}

TEST_F(BvhGpuTest, TriangleSoupMatchesEmbree) {
    const TriMesh m = single(makeSoup(20000, 2));
    compare(m, makeRays(m, kRays, 2), 0xffu, "soup");
}

TEST_F(BvhGpuTest, HeightfieldMatchesEmbree) {
    const TriMesh m = single(makeHeightfield(120));
    compare(m, makeRays(m, kRays, 3), 0xffu, "heightfield");
}

TEST_F(BvhGpuTest, ThinTrianglesMatchEmbree) {
    const TriMesh m = single(makeThin(2000, 4));
    compare(m, makeRays(m, kRays, 4), 0xffu, "thin");
}

// All meshes in one BVH, one mask bit each: masked rays see only their triangles.
TEST_F(BvhGpuTest, RayMasksMatchEmbree) {
    TriMesh m;
    m.append(makeSphere(32, 48, glm::vec3(0.3f, 0.2f, 0.1f), 0.5f), 0x1u);
    m.append(makeSoup(4000, 5), 0x2u);
    m.append(makeHeightfield(60), 0x4u);
    m.append(makeThin(2000, 6), 0x8u);
    const std::vector<Ray> rays = makeRays(m, kRays / 4, 7);
    for (uint32_t mask : {0xffu, 0x1u, 0x6u, 0x8u, 0x10u}) compare(m, rays, mask, "masked scene");
}

// Motion blur (Bvh.h buildMotionBvh): half the triangles of a soup move by up to half the
// scene and turn, a sphere grows; at shutter open, close and between, the motion tree finds
// what Embree finds in the mesh interpolated to that time (boxes bound every time).
TEST_F(BvhGpuTest, MotionTreeMatchesEmbreeAtEveryTime) {
    TriMesh open;
    open.append(makeSoup(6000, 11), 0x1u);
    open.append(makeSphere(24, 32, glm::vec3(0.2f, 0.0f, 0.1f), 0.4f), 0x2u);
    TriMesh close = open;
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (size_t t = 0; t < 6000; ++t) {
        if (t % 2) continue;  // static: exact at every time, without the moving bit
        const glm::vec3 shift = 0.5f * glm::vec3(u(rng), u(rng), u(rng));
        for (int k = 0; k < 3; ++k) {
            glm::vec3& p = close.positions[open.indices[t][k]];
            p = shift + glm::vec3(p.z, p.x, p.y);  // and a turn
        }
    }
    for (size_t v = 3 * 6000; v < close.positions.size(); ++v)
        close.positions[v] =
            glm::vec3(0.2f, 0.0f, 0.1f) + 1.5f * (open.positions[v] - glm::vec3(0.2f, 0.0f, 0.1f));
    const BvhBuild b =
        scene::buildMotionBvh(open.positions, close.positions, open.indices, open.masks);
    ASSERT_EQ(b.motionTriangles.size(), b.triangles.size());
    size_t moving = 0;
    for (const scene::BvhTriangle& r : b.triangles) moving += (r.mask & scene::kBvhMovingBit) != 0;
    EXPECT_EQ(moving, 3000u + (open.indices.size() - 6000));
    const std::vector<Ray> rays = makeRays(open, kRays / 4, 13);
    for (float time : {0.0f, 0.37f, 1.0f}) {
        compare(open, rays, 0xffu, "motion tree", &close, time);
        compare(open, rays, 0x2u, "motion tree, sphere only", &close, time);
    }
}

// The 16-byte-load path for devices without shaderInt64 gives the same answers, and the
// adjacency buffer reaches kernels that call bvh_adjacent().
TEST_F(BvhGpuTest, ShaderVariants) {
    const TriMesh m = single(makeSphere(24, 32, glm::vec3(0.0f), 1.0f));
    const std::vector<Ray> rays = makeRays(m, 4096, 8);
    scene::BvhGpu bvh;
    const BvhBuild build = scene::buildBvh(m.positions, m.indices, m.masks);
    bvh.upload(*sGpu, build);
    auto variant = [&](const char* define) {
        auto shader = sCompiler->compile("tests/data/bvh_trace.comp", {{define, "1"}});
        return sGpu->createPipeline(shader->spirv, shader->reflection, define);
    };
    for (bool anyHit : {false, true}) {
        EXPECT_EQ(trace(bvh, rays, 0xffu, anyHit, *variant("BVH_NO_INT64")),
                  trace(bvh, rays, 0xffu, anyHit));
    }
    std::vector<Ray> dummy(m.indices.size());
    const auto adjacency = trace(bvh, dummy, 0xffu, false, *variant("BVH_ADJACENCY"));
    const auto expected = scene::triangleAdjacency(m.indices);
    for (size_t i = 0; i < expected.size(); ++i)
        ASSERT_EQ(glm::ivec3(adjacency[i]), expected[i]) << "triangle " << i;
}

TEST_F(BvhGpuTest, EmptyAndTinyScenes) {
    TriMesh empty;
    const BvhBuild e = scene::buildBvh(empty.positions, empty.indices, empty.masks);
    scene::BvhGpu bvh;
    bvh.upload(*sGpu, e);
    std::vector<Ray> rays{{glm::vec4(0, 0, -1, 0), glm::vec4(0, 0, 1, INFINITY)}};
    EXPECT_EQ(trace(bvh, rays, 0xffu, false)[0].y, 0xffffffffu);
    EXPECT_EQ(trace(bvh, rays, 0xffu, true)[0].x, 0u);

    TriMesh one;  // a single triangle: the root is a leaf
    one.append(TriMesh{{{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}}, {{0, 1, 2}}, {}}, 0xffu);
    bvh.upload(*sGpu, scene::buildBvh(one.positions, one.indices, one.masks));
    const auto r = trace(bvh, rays, 0xffu, false)[0];
    float t;
    std::memcpy(&t, &r.x, 4);
    EXPECT_EQ(r.y, 0u);
    EXPECT_FLOAT_EQ(t, 1.0f);
    EXPECT_EQ(trace(bvh, rays, 0xffu, true)[0].x, 1u);
}

// CPU-side structure: every triangle referenced, leaf triangles inside their quantised boxes.
TEST(Bvh, LayoutIsConservative) {
    const TriMesh m = single(makeSoup(3000, 9));
    scene::BvhBuildOptions options;
    options.spatialSplits = false;  // leaf boxes then bound whole triangles
    const BvhBuild b = scene::buildBvh(m.positions, m.indices, m.masks, options);
    std::vector<int> seen(m.indices.size(), 0);
    for (const scene::BvhNode& n : b.nodes) {
        uint32_t offset = 0;  // triangles of leaf slots follow each other in slot order
        for (int s = 0; s < 8; ++s) {
            const uint32_t count = std::popcount((n.leafBits >> (3 * s)) & 7u);
            if (count == 0) continue;
            glm::vec3 lo, hi;
            for (int a = 0; a < 3; ++a) {
                const float scale = std::ldexp(1.0f, int(n.exponent[a]) - 127);
                lo[a] = n.origin[a] + float(n.q[a][0][s]) * scale;
                hi[a] = n.origin[a] + float(n.q[a][1][s]) * scale;
            }
            uint32_t mask = 0;
            for (uint32_t k = 0; k < count; ++k) {
                const scene::BvhTriangle& t = b.triangles[n.triangleBase + offset + k];
                ++seen[t.prim];
                mask |= t.mask;
                for (glm::vec3 p : {t.v0, t.v0 + t.e1, t.v0 + t.e2}) {
                    EXPECT_TRUE(glm::all(glm::lessThanEqual(lo, p + 1e-6f)) &&
                                glm::all(glm::lessThanEqual(p - 1e-6f, hi)));
                }
            }
            EXPECT_EQ((n.leafBits >> 24) & mask, mask);
            EXPECT_EQ((n.imask >> s) & 1u, 0u);
            offset += count;
        }
    }
    for (size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], 1) << "triangle " << i;
    EXPECT_THROW(
        scene::buildBvh(m.positions, m.indices, std::vector<uint32_t>(m.indices.size(), 0x100u)),
        UserError);
}

TEST(TriangleAdjacency, TwoTrianglesShareAnEdge) {
    const auto adj = scene::triangleAdjacency({{0, 1, 2}, {2, 1, 3}});
    EXPECT_EQ(adj[0], glm::ivec3(-1, 1, -1));
    EXPECT_EQ(adj[1], glm::ivec3(0, -1, -1));
}

// Three triangles on one edge (a fin): each links to the next around the edge, a cycle.
TEST(TriangleAdjacency, NonManifoldEdgeCycles) {
    const auto adj = scene::triangleAdjacency({{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {5, 5, 6}});
    EXPECT_EQ(adj[0], glm::ivec3(1, -1, -1));
    EXPECT_EQ(adj[1], glm::ivec3(2, -1, -1));
    EXPECT_EQ(adj[2], glm::ivec3(0, -1, -1));
    EXPECT_EQ(adj[3], glm::ivec3(-1, -1, -1));  // degenerate triangle: no neighbours
}

TEST(TriangleAdjacency, ClosedCube) {
    // 8 corners, 12 outward-wound triangles.
    const std::vector<glm::uvec3> cube = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                          {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                          {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    const auto adj = scene::triangleAdjacency(cube);
    for (uint32_t t = 0; t < cube.size(); ++t) {
        std::set<int> distinct;
        for (int k = 0; k < 3; ++k) {
            const int n = adj[t][k];
            ASSERT_GE(n, 0) << "closed mesh has no boundary (triangle " << t << ")";
            distinct.insert(n);
            // The neighbour holds both edge vertices and points back across the same edge.
            const uint32_t a = cube[t][k], b = cube[t][(k + 1) % 3];
            int back = -1;
            for (int j = 0; j < 3; ++j) {
                const uint32_t c = cube[n][j], d = cube[n][(j + 1) % 3];
                if ((c == a && d == b) || (c == b && d == a)) back = adj[n][j];
            }
            EXPECT_EQ(back, int(t)) << "triangle " << t << " edge " << k;
        }
        EXPECT_EQ(distinct.size(), 3u);
    }
}

}  // namespace
