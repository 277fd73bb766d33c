#pragma once
// Triangle BVH for the GLSL traversal in shaders/lib/bvh.glsl. Embree's rtcBuildBVH (SAH,
// high quality = spatial splits) builds an 8-wide tree stored in a variant of the compressed
// wide BVH of Ylitie, Karras and Laine 2017, "Efficient Incoherent Ray Traversal on GPUs
// Through Compressed Wide BVHs": 8-bit quantised child boxes, child slots ordered by ray
// octant. On lavapipe a divergent buffer load is a per-lane loop costing about as much as a
// hundred ALU operations, so the layout minimises load instructions per ray (measurements in
// the header of bvh.glsl and in bench/bench_bvh.cpp).
#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace loom::gpu {
class Bindings;
class Buffer;
class Image;
class Context;
}  // namespace loom::gpu

namespace loom::scene {

// One node = 80 bytes = 5 RGBA32UI texels of the node image (texel i at (i % 8192, i / 8192)).
// On lavapipe an image load is a branch-free 16-byte load per lane while a buffer load is a
// per-lane loop with branches, so node fetches go through the image. 32-bit words:
//  0-2  origin xyz (float bits)     3  exponent x | y << 8 | z << 16 | imask << 24
//  4    index of the first internal child node (internal children are consecutive, in slot
//       order; imask bit s = slot s holds an internal child)
//  5    first triangle of the node (leaf slots' triangles follow each other in slot order)
//  6    leafBits: bits 3s..3s+n-1 set for a leaf in slot s with n triangles (a triangle's
//       offset from word 5 = set bits below its bit) | mask << 24: union of the ray-mask bits
//       of the triangles below the node (a ray whose mask misses it skips the subtree)
//  7    innerRank: bits 3s..3s+2 = offset of slot s's internal child from word 4
//  8-19 quantised child boxes: q[axis][lo, hi][slot], 8 bytes per row; a box decodes as
//       origin + q * 2^(exponent - 127), rounded outwards at build time
// Child slots are assigned by direction (slot bit k set = child towards +axis k) so that the
// traversal visits them nearest first for the ray's octant (Ylitie et al. 2017, Sec. 3.2).
struct BvhNode {
    glm::vec3 origin;
    uint8_t exponent[3];
    uint8_t imask;
    uint32_t childBase;
    uint32_t triangleBase;
    uint32_t leafBits;
    uint32_t innerRank;
    uint8_t q[3][2][8];  // [axis][lo, hi][slot]
};
static_assert(sizeof(BvhNode) == 80);

// Texels per row of the node image (GLSL: BVH_NODE_TEXEL).
constexpr uint32_t kBvhNodeImageWidth = 8192;

// A world-space triangle as the traversal reads it (64 bytes: two 32-byte buffer loads, one
// cache line): Möller–Trumbore with precomputed edges and normal, the caller's primitive id
// and mask. lavapipe binds at most 128 MB per storage buffer: about 2M triangle references.
struct BvhTriangle {
    glm::vec3 v0;
    uint32_t prim;  // index into the input triangle list
    glm::vec3 e1;   // v1 - v0
    uint32_t mask;  // ray-mask bits of the triangle (low 8 bits) | kBvhMovingBit
    glm::vec3 e2;   // v2 - v0
    uint32_t pad0 = 0;
    glm::vec3 ng;  // cross(e1, e2) from the exact vertices, rounded once (slivers stay exact)
    uint32_t pad1 = 0;
};
static_assert(sizeof(BvhTriangle) == 64);

// Set in BvhTriangle::mask when the triangle moves over the shutter (buildMotionBvh): the
// traversal then interpolates it with its shutter-close record.
constexpr uint32_t kBvhMovingBit = 1u << 8;

struct BvhBuildOptions {
    bool spatialSplits = true;      // RTC_BUILD_QUALITY_HIGH (SBVH); false: plain binned SAH
    uint32_t maxLeafSize = 3;       // 1..3 (a leaf slot owns 3 triangle bits in the node)
    float intersectionCost = 1.0f;  // SAH cost of a triangle test relative to a node visit
};

struct BvhStats {
    uint32_t nodes = 0, leaves = 0, triangleRefs = 0, depth = 0;
    double buildMs = 0.0;      // the whole build, adjacency included
    double adjacencyMs = 0.0;  // of which the triangle adjacency
};

struct BvhBuild {
    std::vector<BvhNode> nodes;          // nodes[0] is the root
    std::vector<BvhTriangle> triangles;  // leaf order; one record per reference
    // buildMotionBvh only: the same records at shutter close (empty for a static tree).
    std::vector<BvhTriangle> motionTriangles;
    std::vector<glm::ivec4> adjacency;   // per input triangle (xyz, w = 0), see below
    glm::vec3 lower{0.0f}, upper{0.0f};  // scene bounds
    BvhStats stats;
};

// Maximum tree depth (Embree's maxDepth); the GLSL traversal stack (BVH_STACK_SIZE) holds
// one entry per level.
constexpr uint32_t kBvhMaxDepth = 32;

// Throws UserError for out-of-range indices or masks above 8 bits. An empty triangle list
// gives a single empty root (every ray misses). triMask may be empty (all 0xff).
BvhBuild buildBvh(const std::vector<glm::vec3>& positions, const std::vector<glm::uvec3>& triangles,
                  const std::vector<uint32_t>& triMask, const BvhBuildOptions& options = {});

// Linear motion blur over the shutter, as Embree's triangles with two time steps: vertex i
// moves on the segment from openPositions[i] (shutter open) to closePositions[i] (shutter
// close). Boxes bound both ends, hence every time between (a triangle moving linearly stays in
// the hull of its ends); spatial splits are off, since a split plane clips one time only.
// Records of moving triangles carry kBvhMovingBit and their shutter-close twin in
// motionTriangles (bvh.glsl interpolates at bvh_time).
BvhBuild buildMotionBvh(const std::vector<glm::vec3>& openPositions,
                        const std::vector<glm::vec3>& closePositions,
                        const std::vector<glm::uvec3>& triangles,
                        const std::vector<uint32_t>& triMask, const BvhBuildOptions& options = {});

// For triangle i, component k is the triangle across edge (v[k], v[k+1 mod 3]), or -1 on a
// boundary. On non-manifold edges (more than two triangles) it is the next triangle around
// the edge in input order, so walking the neighbours still visits each of them. Triangles
// with a repeated vertex index have no neighbours and are nobody's neighbour.
std::vector<glm::ivec3> triangleAdjacency(const std::vector<glm::uvec3>& indices);

// The BVH on the device. bind() sets the resources by the GLSL names of bvh.glsl:
// bvh_nodes (RGBA32UI image), bvh_tris and bvh_adjacency (buffers); kernels that never call
// bvh_adjacent() do not reflect bvh_adjacency.
struct BvhGpu {
    std::shared_ptr<gpu::Image> nodes;
    std::shared_ptr<gpu::Buffer> triangles, adjacency;
    uint32_t nodeCount = 0, triangleCount = 0;
    // With `previous`, a second tree (same input triangles, e.g. the previous frame's positions
    // of moving shapes) follows the first in the node image and triangle buffer, at node
    // previousNodeBase and triangle record previousTriangleBase (bvh.glsl's bvh_node_base and
    // bvh_tri_base select it); without, both bases are 0.
    uint32_t previousNodeBase = 0, previousTriangleBase = 0;
    // Distance from a record to its shutter-close twin, in the first and the previous tree
    // (0: that tree has no motion). bvh.glsl's bvh_motion_offset.
    uint32_t motionOffset = 0, previousMotionOffset = 0;
    void upload(gpu::Context& gpu, const BvhBuild& build, const BvhBuild* previous = nullptr);
    void bind(gpu::Bindings& bindings) const;
};

}  // namespace loom::scene
