#include "core/scene/Bvh.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/gpu/Context.h"
#include "core/util/Error.h"

namespace loom::scene {

namespace {

// Nodes produced by the Embree callbacks (thread-local allocator memory, freed with the BVH).
struct BuildNode {
    bool leaf = false;
};

struct BuildInner : BuildNode {
    uint32_t count = 0;
    uint32_t mask = 0;  // union of the subtree's triangle masks (filled after the build)
    BuildNode* children[8] = {};
    RTCBounds bounds[8] = {};
};

struct BuildLeaf : BuildNode {
    uint32_t count = 0;
    uint32_t prims[RTC_BUILD_MAX_PRIMITIVES_PER_LEAF] = {};
};

// Triangle corners by primitive id, contiguous: the split callback runs millions of times.
using Corners = std::array<glm::vec3, 3>;

void* createNode(RTCThreadLocalAllocator alloc, unsigned int childCount, void*) {
    void* mem = rtcThreadLocalAlloc(alloc, sizeof(BuildInner), 16);
    auto* node = new (mem) BuildInner();
    node->count = childCount;
    return node;
}

void setNodeChildren(void* nodePtr, void** children, unsigned int childCount, void*) {
    auto* node = static_cast<BuildInner*>(nodePtr);
    for (unsigned i = 0; i < childCount; ++i)
        node->children[i] = static_cast<BuildNode*>(children[i]);
}

void setNodeBounds(void* nodePtr, const RTCBounds** bounds, unsigned int childCount, void*) {
    auto* node = static_cast<BuildInner*>(nodePtr);
    for (unsigned i = 0; i < childCount; ++i) node->bounds[i] = *bounds[i];
}

void* createLeaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t count,
                 void*) {
    void* mem = rtcThreadLocalAlloc(alloc, sizeof(BuildLeaf), 16);
    auto* leaf = new (mem) BuildLeaf();
    leaf->leaf = true;
    leaf->count = uint32_t(count);
    for (size_t i = 0; i < count; ++i) leaf->prims[i] = prims[i].primID;
    return leaf;
}

// Spatial split (Stich et al. 2009, SBVH): bounds of the triangle's parts on either side of
// the plane, clipped to the reference's current bounds.
void splitPrimitive(const RTCBuildPrimitive* prim, unsigned int dim, float pos, RTCBounds* left,
                    RTCBounds* right, void* user) {
    const Corners& v = static_cast<const Corners*>(user)[prim->primID];
    glm::vec3 lo[2] = {glm::vec3(INFINITY), glm::vec3(INFINITY)};
    glm::vec3 hi[2] = {glm::vec3(-INFINITY), glm::vec3(-INFINITY)};
    for (int i = 0; i < 3; ++i) {
        const glm::vec3& a = v[i];
        const glm::vec3& b = v[i == 2 ? 0 : i + 1];
        const float da = a[dim] - pos, db = b[dim] - pos;
        if (da <= 0.0f) lo[0] = glm::min(lo[0], a), hi[0] = glm::max(hi[0], a);
        if (da >= 0.0f) lo[1] = glm::min(lo[1], a), hi[1] = glm::max(hi[1], a);
        if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {  // edge crosses the plane
            glm::vec3 p = a + (b - a) * (da / (da - db));
            p[dim] = pos;
            for (int side = 0; side < 2; ++side)
                lo[side] = glm::min(lo[side], p), hi[side] = glm::max(hi[side], p);
        }
    }
    const glm::vec3 plo(prim->lower_x, prim->lower_y, prim->lower_z);
    const glm::vec3 phi(prim->upper_x, prim->upper_y, prim->upper_z);
    RTCBounds* out[2] = {left, right};
    for (int side = 0; side < 2; ++side) {
        glm::vec3 l = glm::max(lo[side], plo), h = glm::min(hi[side], phi);
        if (side == 0) h[dim] = std::min(h[dim], pos);
        if (side == 1) l[dim] = std::max(l[dim], pos);
        h = glm::max(h, l);  // an empty side (rounding) stays a valid box
        *out[side] = RTCBounds{l.x, l.y, l.z, 0.0f, h.x, h.y, h.z, 0.0f};
    }
}

uint32_t subtreeMask(BuildNode* node, const std::vector<uint32_t>& masks, uint32_t depth,
                     uint32_t& maxDepth) {
    maxDepth = std::max(maxDepth, depth);
    if (node->leaf) {
        auto* leaf = static_cast<BuildLeaf*>(node);
        uint32_t m = 0;
        for (uint32_t i = 0; i < leaf->count; ++i) m |= masks[leaf->prims[i]];
        return m;
    }
    auto* inner = static_cast<BuildInner*>(node);
    inner->mask = 0;
    for (uint32_t i = 0; i < inner->count; ++i)
        inner->mask |= subtreeMask(inner->children[i], masks, depth + 1, maxDepth);
    return inner->mask;
}

// Power-of-two scale per axis so 255 steps cover the node (Ylitie et al. 2017, Sec. 3.1).
uint8_t quantExponent(float lo, float hi) {
    float extent = hi - lo;
    if (!(extent > 0.0f)) return 1;  // degenerate axis: smallest normal scale
    int e = int(std::ceil(std::log2(extent / 255.0f)));
    // log2 rounding: make sure lo + 255 * 2^e really reaches hi, as the shader computes it.
    while (e < 127 && lo + 255.0f * std::ldexp(1.0f, e) < hi) ++e;
    return uint8_t(std::clamp(e + 127, 1, 254));
}

// Child slot per ray octant: slot bit k set = child lies towards +axis k, so the traversal's
// first slot for a ray with sign bits o is o (nearest corner first). Greedy matching.
std::array<int, 8> assignSlots(const BuildInner& node) {
    glm::vec3 c[8];
    glm::vec3 parent(0.0f);
    for (uint32_t i = 0; i < node.count; ++i) {
        const RTCBounds& b = node.bounds[i];
        c[i] =
            0.5f * glm::vec3(b.lower_x + b.upper_x, b.lower_y + b.upper_y, b.lower_z + b.upper_z);
        parent += c[i] / float(node.count);
    }
    struct Candidate {
        float cost;
        int child, slot;
    };
    std::array<Candidate, 64> candidates;
    uint32_t n = 0;
    for (uint32_t i = 0; i < node.count; ++i) {
        for (int s = 0; s < 8; ++s) {
            glm::vec3 dir((s & 1) ? 1.0f : -1.0f, (s & 2) ? 1.0f : -1.0f, (s & 4) ? 1.0f : -1.0f);
            candidates[n++] = {-glm::dot(c[i] - parent, dir), int(i), s};
        }
    }
    std::sort(candidates.begin(), candidates.begin() + n,
              [](const Candidate& a, const Candidate& b) {
                  return a.cost < b.cost ||
                         (a.cost == b.cost && a.child * 8 + a.slot < b.child * 8 + b.slot);
              });
    std::array<int, 8> slotChild;
    slotChild.fill(-1);
    bool placed[8] = {};
    for (uint32_t k = 0; k < n; ++k) {
        const Candidate& c = candidates[k];
        if (placed[c.child] || slotChild[c.slot] >= 0) continue;
        placed[c.child] = true;
        slotChild[c.slot] = c.child;
    }
    return slotChild;
}

}  // namespace

std::vector<glm::ivec3> triangleAdjacency(const std::vector<glm::uvec3>& indices) {
    // Every half-edge keyed by its undirected edge; sorting groups the uses of an edge in
    // input order (the value breaks ties), then each use links to the next around the edge.
    std::vector<std::pair<uint64_t, uint32_t>> halfEdges;
    halfEdges.reserve(indices.size() * 3);
    for (uint32_t t = 0; t < indices.size(); ++t) {
        const glm::uvec3 v = indices[t];
        if (v.x == v.y || v.y == v.z || v.z == v.x) continue;  // degenerate: no neighbours
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t a = v[k], b = v[(k + 1) % 3];
            const uint64_t key = (uint64_t(std::min(a, b)) << 32) | uint64_t(std::max(a, b));
            halfEdges.emplace_back(key, t * 3 + k);
        }
    }
    std::sort(halfEdges.begin(), halfEdges.end());
    std::vector<glm::ivec3> adjacency(indices.size(), glm::ivec3(-1));
    for (size_t begin = 0, end; begin < halfEdges.size(); begin = end) {
        for (end = begin + 1;
             end < halfEdges.size() && halfEdges[end].first == halfEdges[begin].first;)
            ++end;
        if (end - begin < 2) continue;  // boundary edge
        for (size_t i = begin; i < end; ++i) {
            const uint32_t use = halfEdges[i].second;
            const uint32_t next = halfEdges[i + 1 < end ? i + 1 : begin].second;
            adjacency[use / 3][int(use % 3)] = int(next / 3);
        }
    }
    return adjacency;
}

namespace {
// closePositions: null for a static tree, else every vertex at shutter close (buildMotionBvh).
BvhBuild build(const std::vector<glm::vec3>& positions,
               const std::vector<glm::vec3>* closePositions,
               const std::vector<glm::uvec3>& triangles, const std::vector<uint32_t>& triMask,
               BvhBuildOptions options) {
    if (closePositions) {
        if (closePositions->size() != positions.size())
            throw UserError(
                fmt::format("buildMotionBvh: {} shutter-close positions for {} vertices",
                            closePositions->size(), positions.size()));
        options.spatialSplits = false;  // a split plane would clip one time only
    }
    const auto start = std::chrono::steady_clock::now();
    if (!triMask.empty() && triMask.size() != triangles.size())
        throw UserError(fmt::format("buildBvh: {} triangle masks for {} triangles", triMask.size(),
                                    triangles.size()));
    if (options.maxLeafSize < 1 || options.maxLeafSize > 3)
        throw UserError(
            fmt::format("buildBvh: maxLeafSize {} is not in 1..3", options.maxLeafSize));
    std::vector<uint32_t> masks(triangles.size(), 0xffu);
    for (size_t i = 0; i < triMask.size(); ++i) {
        if (triMask[i] > 0xffu)
            throw UserError(fmt::format(
                "buildBvh: triangle {} has mask 0x{:x}; ray masks have 8 bits", i, triMask[i]));
        masks[i] = triMask[i];
    }

    // Build primitives: one box per triangle, plus spare capacity that Embree fills with
    // spatial-split references while there is room.
    std::vector<RTCBuildPrimitive> prims;
    prims.reserve(options.spatialSplits ? triangles.size() * 3 / 2 : triangles.size());
    glm::vec3 sceneLo(INFINITY), sceneHi(-INFINITY);
    for (uint32_t t = 0; t < triangles.size(); ++t) {
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (int k = 0; k < 3; ++k) {
            if (triangles[t][k] >= positions.size())
                throw UserError(fmt::format("buildBvh: triangle {} uses vertex {} of {}", t,
                                            triangles[t][k], positions.size()));
            const glm::vec3& p = positions[triangles[t][k]];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw UserError(fmt::format("buildBvh: vertex {} is not finite", triangles[t][k]));
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
            if (closePositions) {  // linear motion: the box of both ends bounds every time
                const glm::vec3& q = (*closePositions)[triangles[t][k]];
                if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
                    throw UserError(
                        fmt::format("buildMotionBvh: vertex {} is not finite at shutter close",
                                    triangles[t][k]));
                lo = glm::min(lo, q);
                hi = glm::max(hi, q);
            }
        }
        sceneLo = glm::min(sceneLo, lo);
        sceneHi = glm::max(sceneHi, hi);
        prims.push_back(RTCBuildPrimitive{lo.x, lo.y, lo.z, 0u, hi.x, hi.y, hi.z, t});
    }
    const size_t primCount = prims.size();
    prims.resize(prims.capacity());

    BvhBuild out;
    if (triangles.empty()) {
        out.nodes.push_back(BvhNode{});  // all slots empty: every ray misses
        out.stats.nodes = 1;
        return out;
    }
    out.lower = sceneLo;
    out.upper = sceneHi;

    // Embree objects released on every path; the build nodes live in the RTCBVH's memory.
    std::unique_ptr<RTCDeviceTy, void (*)(RTCDevice)> device(rtcNewDevice(nullptr),
                                                             rtcReleaseDevice);
    if (!device) throw std::runtime_error("buildBvh: rtcNewDevice failed");
    std::unique_ptr<RTCBVHTy, void (*)(RTCBVH)> bvh(rtcNewBVH(device.get()), rtcReleaseBVH);
    std::vector<Corners> corners(triangles.size());
    for (size_t t = 0; t < triangles.size(); ++t)
        corners[t] = {positions[triangles[t].x], positions[triangles[t].y],
                      positions[triangles[t].z]};
    RTCBuildArguments args = rtcDefaultBuildArguments();
    args.byteSize = sizeof(args);
    args.buildQuality = options.spatialSplits ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;
    args.maxBranchingFactor = 8;
    args.maxDepth = kBvhMaxDepth;
    args.sahBlockSize = 1;
    args.minLeafSize = 1;
    args.maxLeafSize = options.maxLeafSize;
    args.traversalCost = 1.0f;
    args.intersectionCost = options.intersectionCost;
    args.bvh = bvh.get();
    args.primitives = prims.data();
    args.primitiveCount = primCount;
    args.primitiveArrayCapacity = prims.size();
    args.createNode = createNode;
    args.setNodeChildren = setNodeChildren;
    args.setNodeBounds = setNodeBounds;
    args.createLeaf = createLeaf;
    args.splitPrimitive = options.spatialSplits ? splitPrimitive : nullptr;
    args.userPtr = corners.data();
    auto* root = static_cast<BuildNode*>(rtcBuildBVH(&args));
    if (!root)
        throw std::runtime_error(fmt::format("buildBvh: rtcBuildBVH failed (Embree error {})",
                                             int(rtcGetDeviceError(device.get()))));

    // A root leaf becomes the single child of an inner root.
    BuildInner rootWrap;
    if (root->leaf) {
        rootWrap.count = 1;
        rootWrap.children[0] = root;
        rootWrap.bounds[0] =
            RTCBounds{sceneLo.x, sceneLo.y, sceneLo.z, 0.0f, sceneHi.x, sceneHi.y, sceneHi.z, 0.0f};
        root = &rootWrap;
    }
    subtreeMask(root, masks, 1, out.stats.depth);

    // Flatten depth first; the internal children of a node get consecutive indices.
    struct Work {
        const BuildInner* node;
        uint32_t index;
    };
    std::vector<Work> work{{static_cast<const BuildInner*>(root), 0}};
    out.nodes.reserve(primCount / 4);
    out.nodes.resize(1);
    out.triangles.reserve(primCount + primCount / 8);
    while (!work.empty()) {
        const Work w = work.back();
        work.pop_back();
        const BuildInner& src = *w.node;
        BvhNode node{};
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (uint32_t i = 0; i < src.count; ++i) {
            const RTCBounds& b = src.bounds[i];
            lo = glm::min(lo, glm::vec3(b.lower_x, b.lower_y, b.lower_z));
            hi = glm::max(hi, glm::vec3(b.upper_x, b.upper_y, b.upper_z));
        }
        node.origin = lo;
        float scale[3];
        for (int a = 0; a < 3; ++a) {
            node.exponent[a] = quantExponent(lo[a], hi[a]);
            scale[a] = std::ldexp(1.0f, int(node.exponent[a]) - 127);
        }
        const std::array<int, 8> slotChild = assignSlots(src);
        uint32_t innerCount = 0;
        for (int s = 0; s < 8; ++s)
            if (slotChild[s] >= 0 && !src.children[slotChild[s]]->leaf) ++innerCount;
        node.childBase = uint32_t(out.nodes.size());
        node.triangleBase = uint32_t(out.triangles.size());
        node.leafBits = src.mask << 24;
        uint32_t nextInner = uint32_t(out.nodes.size());
        out.nodes.resize(out.nodes.size() + innerCount);
        for (int s = 0; s < 8; ++s) {
            if (slotChild[s] < 0) continue;  // empty slot: zero box, zero mask (never hit)
            const BuildNode* child = src.children[slotChild[s]];
            const RTCBounds& b = src.bounds[slotChild[s]];
            const float clo[3] = {b.lower_x, b.lower_y, b.lower_z};
            const float chi[3] = {b.upper_x, b.upper_y, b.upper_z};
            // Conservative quantisation: decoded lo <= child lo, decoded hi >= child hi.
            for (int a = 0; a < 3; ++a) {
                int ql = int(std::floor((clo[a] - lo[a]) / scale[a]));
                int qh = int(std::ceil((chi[a] - lo[a]) / scale[a]));
                ql = std::clamp(ql, 0, 255);
                qh = std::clamp(qh, 0, 255);
                while (ql > 0 && lo[a] + float(ql) * scale[a] > clo[a]) --ql;
                while (qh < 255 && lo[a] + float(qh) * scale[a] < chi[a]) ++qh;
                node.q[a][0][s] = uint8_t(ql);
                node.q[a][1][s] = uint8_t(qh);
            }
            if (child->leaf) {
                const auto* leaf = static_cast<const BuildLeaf*>(child);
                for (uint32_t i = 0; i < leaf->count; ++i) {
                    const uint32_t p = leaf->prims[i];
                    const glm::uvec3 t = triangles[p];
                    const glm::vec3 v0 = positions[t.x];
                    const glm::dvec3 e1 = glm::dvec3(positions[t.y]) - glm::dvec3(v0);
                    const glm::dvec3 e2 = glm::dvec3(positions[t.z]) - glm::dvec3(v0);
                    out.triangles.push_back(BvhTriangle{v0, p, glm::vec3(e1), masks[p],
                                                        glm::vec3(e2), 0u,
                                                        glm::vec3(glm::cross(e1, e2)), 0u});
                    if (closePositions) {
                        const std::vector<glm::vec3>& c = *closePositions;
                        const glm::vec3 c0 = c[t.x];
                        const glm::dvec3 f1 = glm::dvec3(c[t.y]) - glm::dvec3(c0);
                        const glm::dvec3 f2 = glm::dvec3(c[t.z]) - glm::dvec3(c0);
                        out.motionTriangles.push_back(
                            BvhTriangle{c0, p, glm::vec3(f1), masks[p], glm::vec3(f2), 0u,
                                        glm::vec3(glm::cross(f1, f2)), 0u});
                        if (c0 != v0 || c[t.y] != positions[t.y] || c[t.z] != positions[t.z])
                            out.triangles.back().mask |= kBvhMovingBit;
                    }
                    node.leafBits |= 1u << (3 * s + i);
                }
                ++out.stats.leaves;
            } else {
                const auto* inner = static_cast<const BuildInner*>(child);
                node.innerRank |= (nextInner - node.childBase) << (3 * s);
                node.imask |= uint8_t(1u << s);
                work.push_back({inner, nextInner++});
            }
        }
        out.nodes[w.index] = node;
    }
    bvh.reset();
    device.reset();

    const auto adjacencyStart = std::chrono::steady_clock::now();
    std::vector<glm::ivec3> adjacency = triangleAdjacency(triangles);
    out.adjacency.resize(adjacency.size());
    for (size_t i = 0; i < adjacency.size(); ++i) out.adjacency[i] = glm::ivec4(adjacency[i], 0);
    out.stats.adjacencyMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - adjacencyStart)
            .count();

    out.stats.nodes = uint32_t(out.nodes.size());
    out.stats.triangleRefs = uint32_t(out.triangles.size());
    out.stats.buildMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace

BvhBuild buildBvh(const std::vector<glm::vec3>& positions, const std::vector<glm::uvec3>& triangles,
                  const std::vector<uint32_t>& triMask, const BvhBuildOptions& options) {
    return build(positions, nullptr, triangles, triMask, options);
}

BvhBuild buildMotionBvh(const std::vector<glm::vec3>& openPositions,
                        const std::vector<glm::vec3>& closePositions,
                        const std::vector<glm::uvec3>& triangles,
                        const std::vector<uint32_t>& triMask, const BvhBuildOptions& options) {
    return build(openPositions, &closePositions, triangles, triMask, options);
}

void BvhGpu::upload(gpu::Context& gpu, const BvhBuild& build, const BvhBuild* previous) {
    // Nodes as texels of a 2D image, rows of kBvhNodeImageWidth; the last row zero-padded.
    constexpr uint32_t kTexelsPerNode = sizeof(BvhNode) / 16;
    std::vector<BvhNode> allNodes = build.nodes;
    // Each tree's records, then its shutter-close records when it has motion.
    std::vector<BvhTriangle> allTriangles = build.triangles;
    motionOffset = build.motionTriangles.empty() ? 0u : uint32_t(build.triangles.size());
    allTriangles.insert(allTriangles.end(), build.motionTriangles.begin(),
                        build.motionTriangles.end());
    previousNodeBase = previousTriangleBase = previousMotionOffset = 0;
    if (previous) {
        previousNodeBase = uint32_t(allNodes.size());
        previousTriangleBase = uint32_t(allTriangles.size());
        previousMotionOffset =
            previous->motionTriangles.empty() ? 0u : uint32_t(previous->triangles.size());
        allNodes.insert(allNodes.end(), previous->nodes.begin(), previous->nodes.end());
        allTriangles.insert(allTriangles.end(), previous->triangles.begin(),
                            previous->triangles.end());
        allTriangles.insert(allTriangles.end(), previous->motionTriangles.begin(),
                            previous->motionTriangles.end());
    }
    const size_t texels = std::max<size_t>(allNodes.size(), 1) * kTexelsPerNode;
    const size_t rows = (texels + kBvhNodeImageWidth - 1) / kBvhNodeImageWidth;
    if (rows > 16384)
        throw UserError(fmt::format("BVH of {} nodes exceeds the node image ({} rows of {})",
                                    allNodes.size(), 16384, kBvhNodeImageWidth));
    allNodes.resize(rows * kBvhNodeImageWidth / kTexelsPerNode + 1);
    nodes = gpu.createImage(kBvhNodeImageWidth, uint32_t(rows), gpu::Format::RGBA32UI, "bvh_nodes");
    gpu.uploadImage(*nodes, allNodes.data());
    // Every binding must be valid: empty arrays still get a small buffer.
    auto makeBuffer = [&](const void* data, size_t bytes, const char* name) {
        auto buffer = gpu.createBuffer(std::max<size_t>(bytes, 64), name);
        if (bytes) gpu.uploadBuffer(*buffer, data, bytes);
        return buffer;
    };
    triangles =
        makeBuffer(allTriangles.data(), allTriangles.size() * sizeof(BvhTriangle), "bvh_tris");
    adjacency = makeBuffer(build.adjacency.data(), build.adjacency.size() * sizeof(glm::ivec4),
                           "bvh_adjacency");
    nodeCount = uint32_t(build.nodes.size());
    triangleCount = uint32_t(build.triangles.size());
}

void BvhGpu::bind(gpu::Bindings& bindings) const {
    bindings.set("bvh_nodes", nodes).set("bvh_tris", triangles).set("bvh_adjacency", adjacency);
}

}  // namespace loom::scene
