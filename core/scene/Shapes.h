#pragma once
// Built-in shapes shared by the scene loaders (Loom JSON, Mitsuba XML), mesh utilities and the
// PLY reader. Built-ins follow Mitsuba's object-space conventions so that a Mitsuba scene and
// the equivalent Loom scene place them identically:
//   rectangle  [-1,1]^2 in z = 0, normal +z, uv = ((x+1)/2, (y+1)/2)
//   cube       [-1,1]^3, 24 vertices, outward face normals
//   sphere     unit sphere at the origin, poles on +-z, uv = (phi / 2pi, theta / pi)
//   disk       unit disk in z = 0, normal +z
//   cylinder   radius 1, z in [0, 1], open (no caps), outward normals, uv = (phi / 2pi, z)
//   heightfield the rectangle's grid displaced along +z by a height function
#include <functional>
#include <memory>
#include <string>

#include "core/scene/Scene.h"

namespace loom::scene {

Mesh makeRectangle();
Mesh makeCube();
Mesh makeSphere(uint32_t rings = 64, uint32_t segments = 128);
Mesh makeDisk(uint32_t segments = 64);
Mesh makeCylinder(uint32_t segments = 64);
// (nx+1) x (ny+1) vertices over [-1,1]^2, z = height(x, y); smooth vertex normals.
Mesh makeHeightfield(uint32_t nx, uint32_t ny, const std::function<float(float, float)>& height);

// Deterministic "grass" patch of thin bent blades over [-1,1]^2 in z = 0, growing along +z.
// The same parameters give the same triangles on every platform (own hash RNG, no <random>).
struct GrassParams {
    uint32_t blades = 500;
    uint32_t seed = 1;
    float minHeight = 0.1f, maxHeight = 0.3f;
    float width = 0.01f;  // blade width at the root
    float bend = 0.3f;    // tip displacement relative to the height
};
Mesh makeGrass(const GrassParams& params);

// Object-to-world matrix of Mitsuba's cylinder between p0 and p1 (applied after makeCylinder()).
glm::mat4 cylinderTransform(const glm::vec3& p0, const glm::vec3& p1, float radius);

// Height formula for heightfields: + - * / ^, parentheses, numbers, variables x, y, r
// (= sqrt(x^2+y^2)), t (the frame time: a formula with t animates the surface) and pi;
// functions sin cos tan asin acos atan exp log sqrt abs floor fract (1 arg), min max pow atan2
// (2 args), noise(x, y) (deterministic gradient noise in [-1, 1]).
class HeightFormula {
public:
    // Throws UserError "<context>: formula error at column N: ..." on a syntax error.
    static HeightFormula parse(const std::string& text, const std::string& context);
    float operator()(float x, float y, float t = 0.0f) const;
    // Whether the formula reads t (an animated heightfield, re-tessellated every frame).
    bool usesTime() const { return mUsesTime; }

    struct Node;

private:
    std::shared_ptr<const Node> mRoot;
    bool mUsesTime = false;
};

// Area-weighted smooth vertex normals (replaces existing ones).
void computeVertexNormals(Mesh& mesh);
// Reverses the winding and negates vertex normals (Mitsuba flip_normals).
void flipNormals(Mesh& mesh);
// Throws UserError "<context>: ..." on out-of-range indices, non-finite positions or attribute
// arrays whose size differs from the position count.
void validateMesh(const Mesh& mesh, const std::string& context);

// PLY reader (ASCII, binary little and big endian): vertex x/y/z, optional normals nx/ny/nz and
// uvs (u/v, s/t or texture_u/texture_v), faces as index lists (polygons become fans). Other
// elements and properties are skipped. Throws UserError naming the path on any error.
Mesh readPly(const std::string& path);
// OBJ reader (tinyobjloader, in ObjLoader.cpp): all groups merged into one mesh as Mitsuba does;
// vt is flipped (v -> 1 - v) when flipTexCoords, like Mitsuba's flip_tex_coords default.
Mesh readObjMesh(const std::string& path, bool flipTexCoords = true);

}  // namespace loom::scene
