#pragma once
// Triangle BVH for the GLSL traversal in shaders/lib/bvh.glsl. Embree's rtcBuildBVH (SAH,
// high quality = spatial splits) builds an 8-wide tree which is stored in the compressed
// wide BVH layout of Ylitie, Karras and Laine 2017, "Efficient Incoherent Ray Traversal on
// GPUs Through Compressed Wide BVHs": 80-byte nodes with 8-bit quantised child boxes and
// child slots ordered by ray octant. On lavapipe every divergent load is a per-lane loop,
// so bytes fetched per ray is what limits speed; this layout fetches the fewest.
#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace loom::gpu {
class Bindings;
class Buffer;
class Context;
}  // namespace loom::gpu

namespace loom::scene {

// One node = 5 uvec4 (GLSL bvh_nodes.data[5 * i + k]):
//  [0] origin.xyz (float bits), w = exponent x | y << 8 | z << 16 | imask << 24
//  [1] x = first internal child node (low 24 bits) | union of the subtree's triangle masks
//      << 24 (a ray whose mask misses it skips the node), y = first triangle of the node,
//      z, w = meta bytes of children 0-3 and 4-7, each: 0 = empty slot; internal child:
//      0b001 << 5 | (24 + slot); leaf child: unary triangle count << 5 | triangle offset
//  [2] x, y = qlo.x of children 0-7, z, w = qhi.x    [3] same for y    [4] same for z
// Child boxes decode as origin + q * 2^(exponent - 127). Internal children of a node are
// stored contiguously at x, in slot order (imask bit i = slot i is internal).
struct BvhNode {
    glm::vec3 origin;
    uint8_t exponent[3];
    uint8_t imask;
    uint32_t childBase;  // low 24 bits; high 8 bits: subtree mask union
    uint32_t triangleBase;
    uint8_t meta[8];
    uint8_t q[3][2][8];  // [axis][lo, hi][child]
};
static_assert(sizeof(BvhNode) == 80);

// A world-space triangle as the traversal reads it (3 vec4, bvh_tris.data[3 * i + k]):
// Möller–Trumbore with precomputed edges, plus the caller's primitive id and mask.
struct BvhTriangle {
    glm::vec3 v0;
    uint32_t prim;  // index into the input triangle list
    glm::vec3 e1;   // v1 - v0
    uint32_t mask;  // ray-mask bits of the triangle (low 8 bits)
    glm::vec3 e2;   // v2 - v0
    uint32_t pad = 0;
};
static_assert(sizeof(BvhTriangle) == 48);

struct BvhBuildOptions {
    bool spatialSplits = true;  // RTC_BUILD_QUALITY_HIGH (SBVH); false: plain binned SAH
    uint32_t maxLeafSize = 3;   // 1..3 (the node meta stores counts in 3 unary bits)
};

struct BvhStats {
    uint32_t nodes = 0, leaves = 0, triangleRefs = 0, depth = 0;
    double buildMs = 0.0;
};

struct BvhBuild {
    std::vector<BvhNode> nodes;          // nodes[0] is the root
    std::vector<BvhTriangle> triangles;  // leaf order; one record per reference
    std::vector<glm::ivec4> adjacency;   // per input triangle (xyz, w = 0), see below
    glm::vec3 lower{0.0f}, upper{0.0f};  // scene bounds
    BvhStats stats;
};

// Maximum tree depth; the GLSL traversal stack (BVH_STACK_SIZE) is sized from it.
constexpr uint32_t kBvhMaxDepth = 24;

// Throws UserError for out-of-range indices or masks above 8 bits. An empty triangle list
// gives a single empty root (every ray misses). triMask may be empty (all 0xff).
BvhBuild buildBvh(const std::vector<glm::vec3>& positions,
                  const std::vector<glm::uvec3>& triangles,
                  const std::vector<uint32_t>& triMask, const BvhBuildOptions& options = {});

// For triangle i, component k is the triangle across edge (v[k], v[k+1 mod 3]), or -1 on a
// boundary. On non-manifold edges (more than two triangles) it is the next triangle around
// the edge in input order, so walking the neighbours still visits each of them.
std::vector<glm::ivec3> triangleAdjacency(const std::vector<glm::uvec3>& indices);

// The BVH on the device. bind() sets the buffers by the GLSL names of bvh.glsl:
// bvh_nodes, bvh_tris, bvh_adjacency.
struct BvhGpu {
    std::shared_ptr<gpu::Buffer> nodes, triangles, adjacency;
    uint32_t nodeCount = 0, triangleCount = 0;
    void upload(gpu::Context& gpu, const BvhBuild& build);
    void bind(gpu::Bindings& bindings) const;
};

}  // namespace loom::scene
