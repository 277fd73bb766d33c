// GLSL BVH traversal (shaders/lib/bvh.glsl on the default device, lavapipe) against Embree
// rtcIntersect1/rtcOccluded1 on the same CPU and the same rays: coherent primary rays from a
// pinhole camera and incoherent diffuse bounces. Prints Mrays/s and the ratio.
//   bench_bvh [--width W] [--height H] [--reps N] [--detail N] [--spheres N] [--embree 0|1]
//             [--leaf 1..3] [--icost C]   (BvhBuildOptions: maxLeafSize, SAH intersectionCost)
//             [--define NAME=VALUE]...   (shader variants of lib/bvh.glsl; BVH_STATS prints
//             nodes and triangles visited per ray)
//             [--variant NAME=VALUE[,NAME=VALUE]]...  (more kernels, timed interleaved with the
//             base one in the same process: A/B comparisons on a shared machine)
// Rays per CPU-second is the measure to compare on a shared machine; wall-clock rates depend
// on what else runs. Measured on the 2-vCPU dev VM (AMD EPYC, Mesa 22.3 lavapipe, Embree
// 3.13), default scene (661k triangles), 1024x768, quiet moment:
//   rays       GLSL (2 lavapipe threads)  Embree 1T  Embree 2T   GLSL / Embree per CPU-s
//   primary    6.95 Mrays/s               8.81       17.5        0.52
//   diffuse    3.63                       4.81       9.83        0.46
//   shadow     7.25                       7.80       15.4        0.54
// Re-measured (same VM, traversal unchanged, other builds running): per CPU-s primary 4.57 vs
// 8.98 (0.51), diffuse 1.93-2.31 vs 4.38-4.90 (0.44-0.54 across runs), shadow 4.11 vs 7.81
// (0.53); the diffuse ratio varies by +-0.05 from run to run under load.
// Variants tried with --variant (interleaved, same process; per CPU-s, diffuse rays):
//   triangles in an RGBA32UI image instead of the buffer       -14% (primary -5%)
//   postponed triangle tests until half (or 1/4, 3/4) of the   -13% (-5%, -18%); every set
//     subgroup has some (Ylitie et al. 2017 Sec. 4)              slower
//   geometric normal from cross(e1, e2) (6 instead of 8 loads)  -1% (noise)
//   separate "touch" load of each triangle before its test      -30%
//   workgroup 32 or 256 instead of 64                           +-1.5% (noise)
//   LP_NATIVE_VECTOR_WIDTH=128 (SIMD-4)                          same rays per CPU-s
//   maxLeafSize 2, SAH intersectionCost 0.5 or 2 (--leaf/--icost) within noise
//   a queue of rays per invocation: traversal as a step per node, a lane  -23% (primary -38%,
//     whose ray is done takes the next from a shared counter, up to        shadow -36%; 4 rays:
//     16 rays (Aila and Laine 2009, dynamic fetch; 2026-12-06)              -24/-34/-33%)
//   (the step-wise traversal alone, one ray per invocation: shadow -9%, primary and diffuse
//   within noise; neither was kept)
// Ray sorting (2026-12-07, the sets "sorted: ..." below: the same diffuse and shadow rays
// reordered by a key of direction bin and origin cell before upload, sort not timed), per
// CPU-s at 1024x768, GLSL / Embree 1T: unsorted diffuse 1.87 / 4.76; octant then origin 2.02 /
// 4.30; direction (16 bins per axis) then origin 1.75 / 3.38; origin (16 cells per axis) then
// direction 2.27 / 4.92 (+21 %, the best); origin (64) then direction (4) 2.20 / 5.11; shadow by
// direction then origin 3.74 / 7.61 (unsorted 3.52 / 7.92). At 512x384 (a quarter of the rays)
// the best key gains 9 %, within the run-to-run spread: batches of 8 only become coherent when
// a frame has many rays per origin cell, unlike a 128x128 path tracer's bounces.
// BVH_STATS (diffuse): 10.1 nodes and 3.5 triangles per ray, but SIMD-8 batches run 17.4 node
// and 14.1 triangle-loop iterations; yet halving SIMD width changes nothing and perf puts ~21%
// of the kernel on the first load of a triangle (cache misses), so per-lane loads, not lane
// utilisation, bound the traversal on lavapipe.
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <thread>

#include "core/gpu/Context.h"
#include "core/scene/Bvh.h"
#include "core/shader/ShaderCompiler.h"

namespace {

using namespace loom;
using Clock = std::chrono::steady_clock;

struct Ray {
    glm::vec4 o;  // origin, tmin
    glm::vec4 d;  // direction, tmax
};

struct SceneMesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::uvec3> indices;
};

void addSphere(SceneMesh& m, glm::vec3 c, float r, uint32_t rings, uint32_t segments) {
    const uint32_t base = uint32_t(m.positions.size());
    for (uint32_t i = 0; i <= rings; ++i) {
        const float theta = float(M_PI) * float(i) / float(rings);
        for (uint32_t s = 0; s < segments; ++s) {
            const float phi = 2.0f * float(M_PI) * float(s) / float(segments);
            m.positions.push_back(c + r * glm::vec3(std::sin(theta) * std::cos(phi),
                                                    std::cos(theta),
                                                    std::sin(theta) * std::sin(phi)));
        }
    }
    for (uint32_t i = 0; i < rings; ++i) {
        for (uint32_t s = 0; s < segments; ++s) {
            const uint32_t a = base + i * segments + s,
                           b = base + i * segments + (s + 1) % segments;
            if (i > 0) m.indices.push_back({a, b, a + segments});
            if (i + 1 < rings) m.indices.push_back({b, b + segments, a + segments});
        }
    }
}

// Rolling terrain with a field of spheres on it: large open areas plus dense clusters, the
// mix of primary-ray depth complexity a real scene has. ~detail^2 * 2 + spheres triangles.
SceneMesh makeScene(uint32_t detail, uint32_t spheres) {
    SceneMesh m;
    const uint32_t n = detail;
    auto height = [](float x, float z) {
        return 0.6f * std::sin(0.35f * x) * std::cos(0.27f * z) +
               0.15f * std::sin(1.7f * x + 0.4f * z);
    };
    for (uint32_t j = 0; j <= n; ++j) {
        for (uint32_t i = 0; i <= n; ++i) {
            const float x = -20.0f + 40.0f * float(i) / float(n);
            const float z = -20.0f + 40.0f * float(j) / float(n);
            m.positions.push_back({x, height(x, z), z});
        }
    }
    for (uint32_t j = 0; j < n; ++j) {
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            m.indices.push_back({a, c, b});
            m.indices.push_back({b, c, d});
        }
    }
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (uint32_t k = 0; k < spheres; ++k) {
        const float x = -16.0f + 32.0f * u(rng), z = -16.0f + 32.0f * u(rng);
        const float r = 0.3f + 1.2f * u(rng);
        addSphere(m, {x, height(x, z) + 0.7f * r, z}, r, 48, 64);
    }
    return m;
}

// Primary rays in 8x8 tiles, 8 consecutive rays = one row of a tile (one SIMD batch).
std::vector<Ray> primaryRays(uint32_t w, uint32_t h) {
    const glm::vec3 eye(0.0f, 6.0f, 24.0f), target(0.0f, 0.0f, 0.0f);
    const glm::vec3 fwd = glm::normalize(target - eye);
    const glm::vec3 right = glm::normalize(glm::cross(fwd, glm::vec3(0, 1, 0)));
    const glm::vec3 up = glm::cross(right, fwd);
    const float tanHalf = std::tan(0.5f * glm::radians(55.0f)), aspect = float(w) / float(h);
    std::vector<Ray> rays;
    rays.reserve(size_t(w) * h);
    for (uint32_t ty = 0; ty < h; ty += 8) {
        for (uint32_t tx = 0; tx < w; tx += 8) {
            for (uint32_t y = ty; y < std::min(ty + 8, h); ++y) {
                for (uint32_t x = tx; x < std::min(tx + 8, w); ++x) {
                    const float sx =
                        (2.0f * (float(x) + 0.5f) / float(w) - 1.0f) * tanHalf * aspect;
                    const float sy = (1.0f - 2.0f * (float(y) + 0.5f) / float(h)) * tanHalf;
                    const glm::vec3 d = glm::normalize(fwd + sx * right + sy * up);
                    rays.push_back({glm::vec4(eye, 0.0f), glm::vec4(d, INFINITY)});
                }
            }
        }
    }
    return rays;
}

// Ray sorting (the candidate for incoherent rays): the same rays reordered so that an
// 8-lane SIMD batch holds rays of one direction octant from nearby origins (key: octant, then
// the Morton code of the origin in the scene's bounds, 10 bits per axis), or of nearby
// directions first (key: direction bin of 4 bits per axis, then origin). The sort itself is
// not timed; it shows what coherence is worth to each tracer.
uint64_t mortonSpread(uint32_t v) {  // 10 bits -> every third bit of 30
    uint64_t x = v & 0x3ffu;
    x = (x | (x << 16)) & 0x30000ffull;
    x = (x | (x << 8)) & 0x300f00full;
    x = (x | (x << 4)) & 0x30c30c3ull;
    x = (x | (x << 2)) & 0x9249249ull;
    return x;
}

// originBits, directionBits: bits per axis of the origin cell (in the rays' bounds) and the
// direction bin; the key is the direction bin's Morton code above the origin's, or below it
// (originFirst).
std::vector<Ray> sortedRays(const std::vector<Ray>& rays, uint32_t originBits,
                            uint32_t directionBits, bool originFirst) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const Ray& r : rays) {
        lo = glm::min(lo, glm::vec3(r.o));
        hi = glm::max(hi, glm::vec3(r.o));
    }
    const float cells = float(1u << originBits), bins = float(1u << directionBits);
    const glm::vec3 scale = cells / glm::max(hi - lo, glm::vec3(1e-6f));
    auto morton = [](glm::uvec3 q) {
        return mortonSpread(q.x) | (mortonSpread(q.y) << 1) | (mortonSpread(q.z) << 2);
    };
    std::vector<std::pair<uint64_t, uint32_t>> keys(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) {
        const uint64_t origin = morton(
            glm::min(glm::uvec3((glm::vec3(rays[i].o) - lo) * scale), glm::uvec3(cells - 1.0f)));
        const uint64_t dir = morton(glm::min(
            glm::uvec3((glm::vec3(rays[i].d) * 0.5f + 0.5f) * bins), glm::uvec3(bins - 1.0f)));
        keys[i] = {originFirst ? (origin << (3 * directionBits)) | dir
                               : (dir << (3 * originBits)) | origin,
                   uint32_t(i)};
    }
    std::sort(keys.begin(), keys.end());
    std::vector<Ray> out(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) out[i] = rays[keys[i].second];
    return out;
}

// Wall and CPU seconds (all threads of this process: lavapipe's workers count too). On a
// shared machine, rays per CPU-second is the stable measure of traversal efficiency.
struct Timing {
    double wall = INFINITY, cpu = INFINITY;
    void keepBest(const Timing& t) {
        wall = std::min(wall, t.wall);
        cpu = std::min(cpu, t.cpu);
    }
};

double processCpuSeconds() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

class EmbreeScene {
public:
    EmbreeScene(RTCDevice device, const SceneMesh& m) {
        mScene = rtcNewScene(device);
        rtcSetSceneBuildQuality(mScene, RTC_BUILD_QUALITY_HIGH);
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        std::memcpy(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12,
                                            m.positions.size()),
                    m.positions.data(), m.positions.size() * 12);
        std::memcpy(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12,
                                            m.indices.size()),
                    m.indices.data(), m.indices.size() * 12);
        rtcCommitGeometry(g);
        rtcAttachGeometry(mScene, g);
        rtcReleaseGeometry(g);
        rtcCommitScene(mScene);
    }
    ~EmbreeScene() { rtcReleaseScene(mScene); }
    RTCScene scene() const { return mScene; }

private:
    RTCScene mScene;
};

void toRtc(RTCRay& r, const Ray& ray) {
    r.org_x = ray.o.x, r.org_y = ray.o.y, r.org_z = ray.o.z, r.tnear = ray.o.w;
    r.dir_x = ray.d.x, r.dir_y = ray.d.y, r.dir_z = ray.d.z, r.tfar = ray.d.w;
    r.mask = 0xffffffffu, r.flags = 0, r.time = 0.0f;
}

// Embree over all rays with `threads` threads (chunks handed out dynamically); fills the hit
// prim (or ~0u) / occluded flag per ray.
Timing embreeTrace(RTCScene scene, const std::vector<Ray>& rays, bool occlusion, int threads,
                   std::vector<uint32_t>& out) {
    out.assign(rays.size(), 0u);
    std::atomic<size_t> next{0};
    auto worker = [&] {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        constexpr size_t kChunk = 4096;
        for (size_t begin; (begin = next.fetch_add(kChunk)) < rays.size();) {
            const size_t end = std::min(begin + kChunk, rays.size());
            for (size_t i = begin; i < end; ++i) {
                if (occlusion) {
                    RTCRay r;
                    toRtc(r, rays[i]);
                    rtcOccluded1(scene, &ctx, &r);
                    out[i] = r.tfar < 0.0f;
                } else {
                    RTCRayHit rh;
                    toRtc(rh.ray, rays[i]);
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene, &ctx, &rh);
                    out[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? ~0u : rh.hit.primID;
                }
            }
        }
    };
    const auto t0 = Clock::now();
    const double c0 = processCpuSeconds();
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    return {std::chrono::duration<double>(Clock::now() - t0).count(), processCpuSeconds() - c0};
}

struct GpuTracer {
    std::shared_ptr<gpu::Context> gpu;
    std::shared_ptr<gpu::ComputePipeline> pipeline;
    std::vector<std::shared_ptr<gpu::ComputePipeline>> variants;  // --variant kernels
    scene::BvhGpu bvh;

    std::shared_ptr<gpu::Buffer> rayBuf, results;
    uint32_t rayCount = 0;
    bool anyHit = false;
    bool stats = false;  // kernel compiled with BVH_STATS

    void setRays(const std::vector<Ray>& rays, bool any) {
        rayBuf = gpu->createBuffer(rays.size() * sizeof(Ray), "rays");
        gpu->uploadBuffer(*rayBuf, rays.data(), rays.size() * sizeof(Ray));
        results = gpu->createBuffer(rays.size() * sizeof(glm::uvec4), "results");
        rayCount = uint32_t(rays.size());
        anyHit = any;
        run();  // warm-up: lavapipe compiles the kernel on first use
        for (size_t v = 0; v < variants.size(); ++v) run(int(v));
    }

    // variant -1: the base kernel, else --variant number `variant`.
    Timing run(int variant = -1) {
        const gpu::ComputePipeline& p = variant < 0 ? *pipeline : *variants[size_t(variant)];
        gpu::Bindings b;
        bvh.bind(b);
        b.set("rays", rayBuf).set("results", results);
        gpu::PushConstants pc(p);
        pc.set("rayCount", rayCount).set("mask", 0xffu).set("anyHit", uint32_t(anyHit));
        auto cmd = gpu->beginCommands();
        cmd->dispatchThreads(p, b, &pc, rayCount);
        const auto w0 = Clock::now();
        const double c0 = processCpuSeconds();
        gpu->submit(*cmd);
        return {std::chrono::duration<double>(Clock::now() - w0).count(), processCpuSeconds() - c0};
    }

    // Prim (or ~0u) / occluded flag per ray of the last run.
    void readResults(std::vector<uint32_t>& out) {
        std::vector<glm::uvec4> hits(rayCount);
        gpu->downloadBuffer(*results, hits.data(), hits.size() * sizeof(glm::uvec4));
        out.resize(rayCount);
        for (size_t i = 0; i < rayCount; ++i) out[i] = anyHit ? hits[i].x : hits[i].y;
        if (stats && !anyHit) {  // BVH_STATS kernel: nodes, triangles per ray
            double n = 0, t = 0, n8 = 0, t8 = 0, ti = 0;
            for (size_t i = 0; i < rayCount; i += 8) {
                uint32_t mn = 0, mt = 0, mi = 0;
                for (size_t k = i; k < std::min<size_t>(i + 8, rayCount); ++k) {
                    n += hits[k].z, t += hits[k].w;
                    mn = std::max(mn, hits[k].z), mt = std::max(mt, hits[k].w);
                    mi = std::max(mi, hits[k].x);
                }
                n8 += 8.0 * mn, t8 += 8.0 * mt, ti += 8.0 * mi;
            }
            std::printf(
                "  per ray: %.1f nodes, %.1f triangles; SIMD-8 max: %.1f nodes, %.1f "
                "tris; triangle loop iterations %.1f\n",
                n / rayCount, t / rayCount, n8 / rayCount, t8 / rayCount, ti / rayCount);
        }
    }
};
}  // namespace

int main(int argc, char** argv) {
    uint32_t width = 1024, height = 768, detail = 300, spheres = 80;
    int reps = 3;
    bool embreeRuns = true;
    scene::BvhBuildOptions buildOptions;
    ShaderDefines defines;
    std::vector<std::string> variantArgs;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i];
        const uint32_t v = uint32_t(std::atoi(argv[i + 1]));
        if (a == "--width")
            width = v;
        else if (a == "--height")
            height = v;
        else if (a == "--reps")
            reps = int(v);
        else if (a == "--detail")
            detail = v;
        else if (a == "--spheres")
            spheres = v;
        else if (a == "--leaf")
            buildOptions.maxLeafSize = v;
        else if (a == "--icost")
            buildOptions.intersectionCost = float(std::atof(argv[i + 1]));
        else if (a == "--embree")
            embreeRuns = v != 0;
        else if (a == "--define") {  // NAME=VALUE, a shader variant to compare
            const std::string d = argv[i + 1];
            const size_t eq = d.find('=');
            defines[d.substr(0, eq)] = eq == std::string::npos ? "1" : d.substr(eq + 1);
        } else if (a == "--variant") {  // NAME=VALUE[,NAME=VALUE...] on top of --define
            variantArgs.push_back(argv[i + 1]);
        } else {
            std::fprintf(stderr, "unknown option %s\n", argv[i]);
            return 2;
        }
    }

    const SceneMesh mesh = makeScene(detail, spheres);
    const scene::BvhBuild build = scene::buildBvh(mesh.positions, mesh.indices, {}, buildOptions);
    std::printf(
        "scene: %zu triangles; BVH8: %u nodes (%.1f MB), %u leaves, %u triangle refs "
        "(%.1f MB), depth %u, built in %.0f ms\n",
        mesh.indices.size(), build.stats.nodes,
        build.nodes.size() * double(sizeof(scene::BvhNode)) / 1e6, build.stats.leaves,
        build.stats.triangleRefs, build.triangles.size() * double(sizeof(scene::BvhTriangle)) / 1e6,
        build.stats.depth, build.stats.buildMs);

    GpuTracer gpuTracer;
    gpuTracer.gpu = gpu::Context::create();
    ShaderCompiler compiler({LOOM_SOURCE_DIR "/shaders", LOOM_SOURCE_DIR}, "");
    auto shader = compiler.compile("tests/data/bvh_trace.comp", defines);
    gpuTracer.pipeline =
        gpuTracer.gpu->createPipeline(shader->spirv, shader->reflection, "bvh_trace");
    gpuTracer.bvh.upload(*gpuTracer.gpu, build);
    gpuTracer.stats = defines.count("BVH_STATS") > 0;
    for (const std::string& v : variantArgs) {
        ShaderDefines vd = defines;
        for (size_t b = 0, e; b < v.size(); b = e + 1) {
            e = std::min(v.find(',', b), v.size());
            const std::string d = v.substr(b, e - b);
            const size_t eq = d.find('=');
            vd[d.substr(0, eq)] = eq == std::string::npos ? "1" : d.substr(eq + 1);
        }
        auto vs = compiler.compile("tests/data/bvh_trace.comp", vd);
        gpuTracer.variants.push_back(
            gpuTracer.gpu->createPipeline(vs->spirv, vs->reflection, "bvh_trace"));
    }
    const char* lpThreads = std::getenv("LP_NUM_THREADS");
    std::printf("device: %s (LP_NUM_THREADS=%s), CPU threads: %u\n",
                gpuTracer.gpu->deviceInfo().name.c_str(), lpThreads ? lpThreads : "default",
                std::thread::hardware_concurrency());

    RTCDevice device = rtcNewDevice(nullptr);
    const auto e0 = Clock::now();
    EmbreeScene embree(device, mesh);
    std::printf("Embree scene (RTC_BUILD_QUALITY_HIGH) built in %.0f ms\n",
                std::chrono::duration<double, std::milli>(Clock::now() - e0).count());

    // Ray sets: primary, then diffuse bounces from the primary hits (Embree's hits, so both
    // tracers get identical rays), then shadow rays towards a point light from those hits.
    std::vector<Ray> primary = primaryRays(width, height);
    std::vector<Ray> diffuse, shadow;
    {
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        const glm::vec3 light(5.0f, 12.0f, 6.0f);
        for (const Ray& r : primary) {
            RTCRayHit rh;
            toRtc(rh.ray, r);
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(embree.scene(), &ctx, &rh);
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
            const glm::vec3 p = glm::vec3(r.o) + rh.ray.tfar * glm::vec3(r.d);
            glm::vec3 n = glm::normalize(glm::vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
            if (glm::dot(n, glm::vec3(r.d)) > 0.0f) n = -n;
            // Cosine-weighted direction about n (Malley's method).
            const float r1 = u(rng), phi = 2.0f * float(M_PI) * u(rng);
            const glm::vec3 t = glm::normalize(std::abs(n.x) > 0.5f ? glm::cross(n, {0, 1, 0})
                                                                    : glm::cross(n, {1, 0, 0}));
            const glm::vec3 b = glm::cross(n, t);
            const glm::vec3 d =
                std::sqrt(r1) * (std::cos(phi) * t + std::sin(phi) * b) + std::sqrt(1.0f - r1) * n;
            const glm::vec3 o = p + 1e-3f * n;
            diffuse.push_back({glm::vec4(o, 0.0f), glm::vec4(glm::normalize(d), INFINITY)});
            const glm::vec3 toLight = light - o;
            shadow.push_back(
                {glm::vec4(o, 0.0f), glm::vec4(glm::normalize(toLight), glm::length(toLight))});
        }
    }

    struct Set {
        const char* name;
        const std::vector<Ray>* rays;
        bool anyHit;
    };
    const std::vector<Ray> diffuseByOctant = sortedRays(diffuse, 10, 1, false);
    const std::vector<Ray> diffuseByDirection = sortedRays(diffuse, 10, 4, false);
    const std::vector<Ray> diffuseByOrigin = sortedRays(diffuse, 4, 4, true);
    const std::vector<Ray> diffuseByOrigin6 = sortedRays(diffuse, 6, 2, true);
    const std::vector<Ray> shadowByDirection = sortedRays(shadow, 10, 4, false);
    const Set sets[] = {{"primary (coherent)", &primary, false},
                        {"diffuse bounce (incoherent)", &diffuse, false},
                        {"shadow, any hit", &shadow, true},
                        {"diffuse sorted: octant, origin", &diffuseByOctant, false},
                        {"diffuse sorted: dir/16, origin", &diffuseByDirection, false},
                        {"diffuse sorted: origin/16, dir/16", &diffuseByOrigin, false},
                        {"diffuse sorted: origin/64, dir/4", &diffuseByOrigin6, false},
                        {"shadow sorted: dir/16, origin", &shadowByDirection, true}};
    // Reps interleave the tracers so that load from other processes hits all of them alike;
    // best of reps for wall time and CPU time separately.
    std::printf("\nMrays/s (wall clock, best of %d) and Mrays per CPU-second (all threads):\n",
                reps);
    std::printf("%-28s %8s | %7s %7s %7s | %7s %7s %7s | %6s %6s %6s | %6s\n", "rays", "count",
                "GLSL", "Emb 1T", "Emb 2T", "GLSL", "Emb 1T", "Emb 2T", "G/1T", "G/2T", "G/1T",
                "differ");
    std::printf("%-28s %8s | %23s | %23s | %13s %6s |\n", "", "", "wall Mrays/s", "Mrays per CPU-s",
                "wall ratio", "CPU");
    for (const Set& s : sets) {
        std::vector<uint32_t> g, e1, e2;
        gpuTracer.setRays(*s.rays, s.anyHit);
        Timing tg, t1, t2;
        std::vector<Timing> tv(gpuTracer.variants.size());
        for (int r = 0; r < reps; ++r) {
            tg.keepBest(gpuTracer.run());
            for (size_t v = 0; v < tv.size(); ++v) tv[v].keepBest(gpuTracer.run(int(v)));
            if (r == 0 || embreeRuns)
                t1.keepBest(embreeTrace(embree.scene(), *s.rays, s.anyHit, 1, e1));
            if (embreeRuns) t2.keepBest(embreeTrace(embree.scene(), *s.rays, s.anyHit, 2, e2));
        }
        gpuTracer.readResults(g);
        size_t differ = 0;
        for (size_t i = 0; i < g.size(); ++i) differ += g[i] != e1[i];
        const double n = double(s.rays->size()) * 1e-6;
        std::printf(
            "%-28s %8zu | %7.2f %7.2f %7.2f | %7.2f %7.2f %7.2f | %6.2f %6.2f %6.2f | %6zu\n",
            s.name, s.rays->size(), n / tg.wall, n / t1.wall, n / t2.wall, n / tg.cpu, n / t1.cpu,
            n / t2.cpu, t1.wall / tg.wall, t2.wall / tg.wall, t1.cpu / tg.cpu, differ);
        for (size_t v = 0; v < tv.size(); ++v)
            std::printf("  variant %-36s GLSL %6.2f Mrays/s wall, %6.2f per CPU-s (%+.1f%%)\n",
                        variantArgs[v].c_str(), n / tv[v].wall, n / tv[v].cpu,
                        100.0 * (tg.cpu / tv[v].cpu - 1.0));
    }
    rtcReleaseDevice(device);
    return 0;
}
