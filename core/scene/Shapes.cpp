#include "core/scene/Shapes.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>

#include <fmt/format.h>

#include "core/util/Error.h"

namespace loom::scene {

namespace {

// PCG hash (O'Neill 2014, the "RXS-M-XS" output of one LCG step): a stateless integer hash with
// good avalanche, used for the deterministic generators and the noise lattice.
uint32_t pcgHash(uint32_t v) {
    uint32_t state = v * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

class HashRng {
public:
    explicit HashRng(uint32_t seed) : mState(pcgHash(seed ^ 0x9e3779b9u)) {}
    // Uniform in [0, 1) with 24 bits.
    float next() {
        mState = pcgHash(mState);
        return float(mState >> 8) * (1.0f / 16777216.0f);
    }

private:
    uint32_t mState;
};

// 2D gradient noise (Perlin 2002 style with a quintic fade) on the integer lattice.
float gradientNoise(float x, float y) {
    auto grad = [](int ix, int iy, float dx, float dy) {
        uint32_t h = pcgHash(uint32_t(ix) * 73856093u ^ pcgHash(uint32_t(iy) * 19349663u));
        float angle = float(h) * (2.0f * std::numbers::pi_v<float> / 4294967296.0f);
        return std::cos(angle) * dx + std::sin(angle) * dy;
    };
    auto fade = [](float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); };
    float fx = std::floor(x), fy = std::floor(y);
    int ix = int(fx), iy = int(fy);
    float dx = x - fx, dy = y - fy;
    float n00 = grad(ix, iy, dx, dy), n10 = grad(ix + 1, iy, dx - 1, dy);
    float n01 = grad(ix, iy + 1, dx, dy - 1), n11 = grad(ix + 1, iy + 1, dx - 1, dy - 1);
    float u = fade(dx), v = fade(dy);
    float nx0 = n00 + u * (n10 - n00), nx1 = n01 + u * (n11 - n01);
    // The 2D gradient-noise range is about +-0.7; scale towards +-1.
    return std::clamp(1.4f * (nx0 + v * (nx1 - nx0)), -1.0f, 1.0f);
}

}  // namespace

// ------------------------------------------------------------------------------------------
// Built-in tessellations

Mesh makeRectangle() {
    Mesh m;
    m.name = "rectangle";
    m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    m.normals.assign(4, glm::vec3(0, 0, 1));
    m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m.indices = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

Mesh makeCube() {
    Mesh m;
    m.name = "cube";
    // One quad per face with tangents (u, v) such that cross(u, v) = n (outward, CCW winding).
    const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int axis = 0; axis < 3; ++axis)
        for (float sign : {1.0f, -1.0f}) {
            glm::vec3 n = axes[axis] * sign;
            glm::vec3 u = axes[(axis + 1) % 3] * sign;
            glm::vec3 v = glm::cross(n, u);
            auto base = uint32_t(m.positions.size());
            m.positions.push_back(n - u - v);
            m.positions.push_back(n + u - v);
            m.positions.push_back(n + u + v);
            m.positions.push_back(n - u + v);
            for (int i = 0; i < 4; ++i) m.normals.push_back(n);
            m.uvs.insert(m.uvs.end(), {{0, 0}, {1, 0}, {1, 1}, {0, 1}});
            m.indices.push_back({base, base + 1, base + 2});
            m.indices.push_back({base, base + 2, base + 3});
        }
    return m;
}

Mesh makeSphere(uint32_t rings, uint32_t segments) {
    rings = std::max(rings, 2u);
    segments = std::max(segments, 3u);
    Mesh m;
    m.name = "sphere";
    // Vertex rows of constant theta (0 = +z pole); the seam column is duplicated for the uvs.
    for (uint32_t i = 0; i <= rings; ++i) {
        float theta = std::numbers::pi_v<float> * float(i) / float(rings);
        for (uint32_t j = 0; j <= segments; ++j) {
            float phi = 2.0f * std::numbers::pi_v<float> * float(j) / float(segments);
            glm::vec3 p(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                        std::cos(theta));
            m.positions.push_back(p);
            m.normals.push_back(p);
            m.uvs.push_back({float(j) / float(segments), float(i) / float(rings)});
        }
    }
    // cross(d/dtheta, d/dphi) points outwards: triangles (a, c, d) and (a, d, b). The pole rows
    // would give degenerate triangles, which are skipped.
    for (uint32_t i = 0; i < rings; ++i)
        for (uint32_t j = 0; j < segments; ++j) {
            uint32_t a = i * (segments + 1) + j, b = a + 1, c = a + segments + 1, d = c + 1;
            if (i + 1 < rings) m.indices.push_back({a, c, d});
            if (i > 0) m.indices.push_back({a, d, b});
        }
    return m;
}

Mesh makeDisk(uint32_t segments) {
    segments = std::max(segments, 3u);
    Mesh m;
    m.name = "disk";
    m.positions.push_back({0, 0, 0});
    m.normals.push_back({0, 0, 1});
    m.uvs.push_back({0, 0});
    for (uint32_t j = 0; j <= segments; ++j) {
        float phi = 2.0f * std::numbers::pi_v<float> * float(j) / float(segments);
        m.positions.push_back({std::cos(phi), std::sin(phi), 0});
        m.normals.push_back({0, 0, 1});
        m.uvs.push_back({1.0f, float(j) / float(segments)});  // Mitsuba: uv = (r, phi / 2pi)
    }
    for (uint32_t j = 0; j < segments; ++j) m.indices.push_back({0, j + 1, j + 2});
    return m;
}

Mesh makeCylinder(uint32_t segments) {
    segments = std::max(segments, 3u);
    Mesh m;
    m.name = "cylinder";
    for (float z : {0.0f, 1.0f})
        for (uint32_t j = 0; j <= segments; ++j) {
            float phi = 2.0f * std::numbers::pi_v<float> * float(j) / float(segments);
            m.positions.push_back({std::cos(phi), std::sin(phi), z});
            m.normals.push_back({std::cos(phi), std::sin(phi), 0});
            m.uvs.push_back({float(j) / float(segments), z});
        }
    for (uint32_t j = 0; j < segments; ++j) {
        uint32_t a = j, b = j + 1, c = a + segments + 1, d = c + 1;
        m.indices.push_back({a, b, d});
        m.indices.push_back({a, d, c});
    }
    return m;
}

Mesh makeHeightfield(uint32_t nx, uint32_t ny, const std::function<float(float, float)>& height) {
    nx = std::max(nx, 1u);
    ny = std::max(ny, 1u);
    Mesh m;
    m.name = "heightfield";
    for (uint32_t j = 0; j <= ny; ++j)
        for (uint32_t i = 0; i <= nx; ++i) {
            float x = -1.0f + 2.0f * float(i) / float(nx), y = -1.0f + 2.0f * float(j) / float(ny);
            m.positions.push_back({x, y, height(x, y)});
            m.uvs.push_back({(x + 1.0f) * 0.5f, (y + 1.0f) * 0.5f});
        }
    for (uint32_t j = 0; j < ny; ++j)
        for (uint32_t i = 0; i < nx; ++i) {
            uint32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
            m.indices.push_back({a, b, d});
            m.indices.push_back({a, d, c});
        }
    computeVertexNormals(m);
    return m;
}

Mesh makeGrass(const GrassParams& p) {
    Mesh m;
    m.name = "grass";
    HashRng rng(p.seed);
    for (uint32_t blade = 0; blade < p.blades; ++blade) {
        glm::vec3 root(2.0f * rng.next() - 1.0f, 2.0f * rng.next() - 1.0f, 0.0f);
        float facing = 2.0f * std::numbers::pi_v<float> * rng.next();
        float h = p.minHeight + (p.maxHeight - p.minHeight) * rng.next();
        float bend = p.bend * (0.5f + rng.next());
        glm::vec3 side(std::cos(facing), std::sin(facing), 0.0f);  // across the blade
        glm::vec3 lean(-side.y, side.x, 0.0f);                     // bending direction
        // Point on the blade's spine at relative height t (quadratic bend towards the tip).
        auto spine = [&](float t) {
            return root + lean * (bend * h * t * t) + glm::vec3(0, 0, h * t);
        };
        auto base = uint32_t(m.positions.size());
        float w = 0.5f * p.width;
        m.positions.push_back(spine(0.0f) - side * w);
        m.positions.push_back(spine(0.0f) + side * w);
        m.positions.push_back(spine(0.5f) - side * (0.6f * w));
        m.positions.push_back(spine(0.5f) + side * (0.6f * w));
        m.positions.push_back(spine(1.0f));
        for (float v : {0.0f, 0.0f, 0.5f, 0.5f, 1.0f}) m.uvs.push_back({0.5f, 1.0f - v});
        m.uvs[base].x = 0.0f;
        m.uvs[base + 1].x = 1.0f;
        m.uvs[base + 2].x = 0.2f;
        m.uvs[base + 3].x = 0.8f;
        m.indices.push_back({base, base + 1, base + 3});
        m.indices.push_back({base, base + 3, base + 2});
        m.indices.push_back({base + 2, base + 3, base + 4});
    }
    return m;
}

glm::mat4 cylinderTransform(const glm::vec3& p0, const glm::vec3& p1, float radius) {
    glm::vec3 d = p1 - p0;
    float length = glm::length(d);
    glm::vec3 n = length > 0.0f ? d / length : glm::vec3(0, 0, 1);
    // Orthonormal basis around n as Mitsuba's coordinate_system() builds it (Duff et al. 2017),
    // so that the cylinder's uv seam matches Mitsuba's.
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    glm::vec3 s(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    glm::vec3 t(b, sign + n.y * n.y * a, -n.y);
    glm::mat4 m(1.0f);
    m[0] = glm::vec4(s * radius, 0.0f);
    m[1] = glm::vec4(t * radius, 0.0f);
    m[2] = glm::vec4(n * length, 0.0f);
    m[3] = glm::vec4(p0, 1.0f);
    return m;
}

// ------------------------------------------------------------------------------------------
// Height formulas

struct HeightFormula::Node {
    enum Kind {
        Number,
        VarX,
        VarY,
        VarR,
        VarT,
        Add,
        Sub,
        Mul,
        Div,
        Pow,
        Neg,
        Call1,
        Call2
    } kind = Number;
    float value = 0.0f;
    float (*fn1)(float) = nullptr;
    float (*fn2)(float, float) = nullptr;
    std::shared_ptr<const Node> a, b;

    float eval(float x, float y, float t) const {
        switch (kind) {
            case Number:
                return value;
            case VarX:
                return x;
            case VarY:
                return y;
            case VarR:
                return std::sqrt(x * x + y * y);
            case VarT:
                return t;
            case Add:
                return a->eval(x, y, t) + b->eval(x, y, t);
            case Sub:
                return a->eval(x, y, t) - b->eval(x, y, t);
            case Mul:
                return a->eval(x, y, t) * b->eval(x, y, t);
            case Div:
                return a->eval(x, y, t) / b->eval(x, y, t);
            case Pow:
                return std::pow(a->eval(x, y, t), b->eval(x, y, t));
            case Neg:
                return -a->eval(x, y, t);
            case Call1:
                return fn1(a->eval(x, y, t));
            case Call2:
                return fn2(a->eval(x, y, t), b->eval(x, y, t));
        }
        return 0.0f;
    }
};

namespace {

using NodePtr = std::shared_ptr<const HeightFormula::Node>;

// Recursive-descent parser: expr = term {(+|-) term}; term = unary {(*|/) unary};
// unary = (-|+) unary | power; power = primary [^ unary]; primary = number | name | name(args)
// | (expr).
class FormulaParser {
public:
    FormulaParser(const std::string& text, const std::string& context)
        : mText(text), mContext(context) {}

    NodePtr parse() {
        NodePtr n = expr();
        skipWs();
        if (mPos < mText.size()) fail(fmt::format("unexpected '{}'", mText[mPos]));
        return n;
    }
    bool usesTime() const { return mUsesTime; }

private:
    const std::string& mText;
    const std::string& mContext;
    size_t mPos = 0;
    bool mUsesTime = false;

    [[noreturn]] void fail(const std::string& what) const {
        throw UserError(fmt::format("{}: height formula error at column {}: {} in \"{}\"", mContext,
                                    mPos + 1, what, mText));
    }
    void skipWs() {
        while (mPos < mText.size() && std::isspace(static_cast<unsigned char>(mText[mPos]))) ++mPos;
    }
    bool accept(char c) {
        skipWs();
        if (mPos < mText.size() && mText[mPos] == c) {
            ++mPos;
            return true;
        }
        return false;
    }
    static NodePtr binary(HeightFormula::Node::Kind kind, NodePtr a, NodePtr b) {
        auto n = std::make_shared<HeightFormula::Node>();
        n->kind = kind;
        n->a = std::move(a);
        n->b = std::move(b);
        return n;
    }
    NodePtr expr() {
        NodePtr n = term();
        while (true) {
            if (accept('+'))
                n = binary(HeightFormula::Node::Add, n, term());
            else if (accept('-'))
                n = binary(HeightFormula::Node::Sub, n, term());
            else
                return n;
        }
    }
    NodePtr term() {
        NodePtr n = unary();
        while (true) {
            if (accept('*'))
                n = binary(HeightFormula::Node::Mul, n, unary());
            else if (accept('/'))
                n = binary(HeightFormula::Node::Div, n, unary());
            else
                return n;
        }
    }
    NodePtr unary() {
        if (accept('-')) return binary(HeightFormula::Node::Neg, unary(), nullptr);
        if (accept('+')) return unary();
        NodePtr base = primary();
        if (accept('^')) return binary(HeightFormula::Node::Pow, base, unary());
        return base;
    }
    NodePtr primary() {
        skipWs();
        if (mPos >= mText.size()) fail("unexpected end of formula");
        char c = mText[mPos];
        if (accept('(')) {
            NodePtr n = expr();
            if (!accept(')')) fail("expected ')'");
            return n;
        }
        if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
            const char* begin = mText.c_str() + mPos;
            char* end = nullptr;
            float v = std::strtof(begin, &end);
            if (end == begin) fail("malformed number");
            mPos += size_t(end - begin);
            auto n = std::make_shared<HeightFormula::Node>();
            n->value = v;
            return n;
        }
        if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
            size_t start = mPos;
            while (mPos < mText.size() &&
                   (std::isalnum(static_cast<unsigned char>(mText[mPos])) || mText[mPos] == '_'))
                ++mPos;
            std::string name = mText.substr(start, mPos - start);
            auto n = std::make_shared<HeightFormula::Node>();
            if (name == "x")
                n->kind = HeightFormula::Node::VarX;
            else if (name == "y")
                n->kind = HeightFormula::Node::VarY;
            else if (name == "r")
                n->kind = HeightFormula::Node::VarR;
            else if (name == "t") {
                n->kind = HeightFormula::Node::VarT;
                mUsesTime = true;
            } else if (name == "pi")
                n->value = std::numbers::pi_v<float>;
            else
                return call(name, start);
            return n;
        }
        fail(fmt::format("unexpected '{}'", c));
    }
    NodePtr call(const std::string& name, size_t start) {
        static const std::pair<const char*, float (*)(float)> kFn1[] = {
            {"sin", [](float v) { return std::sin(v); }},
            {"cos", [](float v) { return std::cos(v); }},
            {"tan", [](float v) { return std::tan(v); }},
            {"asin", [](float v) { return std::asin(v); }},
            {"acos", [](float v) { return std::acos(v); }},
            {"atan", [](float v) { return std::atan(v); }},
            {"exp", [](float v) { return std::exp(v); }},
            {"log", [](float v) { return std::log(v); }},
            {"sqrt", [](float v) { return std::sqrt(v); }},
            {"abs", [](float v) { return std::fabs(v); }},
            {"floor", [](float v) { return std::floor(v); }},
            {"fract", [](float v) { return v - std::floor(v); }}};
        static const std::pair<const char*, float (*)(float, float)> kFn2[] = {
            {"min", [](float a, float b) { return std::min(a, b); }},
            {"max", [](float a, float b) { return std::max(a, b); }},
            {"pow", [](float a, float b) { return std::pow(a, b); }},
            {"atan2", [](float a, float b) { return std::atan2(a, b); }},
            {"noise", [](float a, float b) { return gradientNoise(a, b); }}};
        auto n = std::make_shared<HeightFormula::Node>();
        for (auto& [fname, fn] : kFn1)
            if (name == fname) {
                n->kind = HeightFormula::Node::Call1;
                n->fn1 = fn;
            }
        for (auto& [fname, fn] : kFn2)
            if (name == fname) {
                n->kind = HeightFormula::Node::Call2;
                n->fn2 = fn;
            }
        if (n->kind == HeightFormula::Node::Number) {
            mPos = start;
            fail("unknown name '" + name +
                 "' (variables: x, y, r, pi; functions: sin cos tan asin acos atan exp log sqrt "
                 "abs floor fract min max pow atan2 noise)");
        }
        if (!accept('(')) fail("expected '(' after " + name);
        n->a = expr();
        if (n->kind == HeightFormula::Node::Call2) {
            if (!accept(',')) fail(name + " takes two arguments");
            n->b = expr();
        }
        if (!accept(')')) fail("expected ')'");
        return n;
    }
};

}  // namespace

HeightFormula HeightFormula::parse(const std::string& text, const std::string& context) {
    HeightFormula f;
    FormulaParser parser(text, context);
    f.mRoot = parser.parse();
    f.mUsesTime = parser.usesTime();
    return f;
}

float HeightFormula::operator()(float x, float y, float t) const {
    return mRoot ? mRoot->eval(x, y, t) : 0.0f;
}

// ------------------------------------------------------------------------------------------
// Mesh utilities

void computeVertexNormals(Mesh& mesh) {
    mesh.normals.assign(mesh.positions.size(), glm::vec3(0.0f));
    for (const glm::uvec3& t : mesh.indices) {
        const glm::vec3 &p0 = mesh.positions[t.x], &p1 = mesh.positions[t.y],
                        &p2 = mesh.positions[t.z];
        glm::vec3 n = glm::cross(p1 - p0, p2 - p0);  // length = 2 * area: area weighting
        mesh.normals[t.x] += n;
        mesh.normals[t.y] += n;
        mesh.normals[t.z] += n;
    }
    for (glm::vec3& n : mesh.normals) {
        float len = glm::length(n);
        n = len > 0.0f ? n / len : glm::vec3(0, 0, 1);
    }
}

void flipNormals(Mesh& mesh) {
    for (glm::uvec3& t : mesh.indices) std::swap(t.y, t.z);
    for (glm::vec3& n : mesh.normals) n = -n;
}

void validateMesh(const Mesh& mesh, const std::string& context) {
    size_t n = mesh.positions.size();
    if (!mesh.normals.empty() && mesh.normals.size() != n)
        throw UserError(
            fmt::format("{}: {} normals for {} vertices", context, mesh.normals.size(), n));
    if (!mesh.uvs.empty() && mesh.uvs.size() != n)
        throw UserError(fmt::format("{}: {} uvs for {} vertices", context, mesh.uvs.size(), n));
    for (size_t i = 0; i < n; ++i) {
        const glm::vec3& p = mesh.positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw UserError(fmt::format("{}: vertex {} has a non-finite position", context, i));
    }
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
        const glm::uvec3& t = mesh.indices[i];
        if (t.x >= n || t.y >= n || t.z >= n)
            throw UserError(fmt::format("{}: triangle {} references vertex {} but the mesh has {}",
                                        context, i, std::max({t.x, t.y, t.z}), n));
    }
}

// ------------------------------------------------------------------------------------------
// PLY reader

namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parsePlyType(const std::string& s, PlyType& t) {
    static const std::pair<const char*, PlyType> kTypes[] = {
        {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64}};
    for (auto& [name, type] : kTypes)
        if (s == name) {
            t = type;
            return true;
        }
    return false;
}

size_t plyTypeSize(PlyType t) {
    switch (t) {
        case PlyType::Int8:
        case PlyType::UInt8:
            return 1;
        case PlyType::Int16:
        case PlyType::UInt16:
            return 2;
        case PlyType::Int32:
        case PlyType::UInt32:
        case PlyType::Float32:
            return 4;
        case PlyType::Float64:
            return 8;
    }
    return 0;
}

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;
    bool isList = false;
    PlyType countType = PlyType::UInt8;
};

struct PlyElement {
    std::string name;
    size_t count = 0;
    std::vector<PlyProperty> properties;
};

enum class PlyFormat { Ascii, BinaryLittle, BinaryBig };

// Reads values one at a time from the body of a PLY file in any of the three encodings.
class PlyBody {
public:
    PlyBody(const std::string& data, size_t offset, PlyFormat format, const std::string& path)
        : mData(data), mPos(offset), mFormat(format), mPath(path) {}

    double read(PlyType type) {
        if (mFormat == PlyFormat::Ascii) return readAscii();
        size_t size = plyTypeSize(type);
        if (mPos + size > mData.size())
            throw UserError(mPath + ": PLY file is truncated (binary data ends early)");
        unsigned char bytes[8];
        std::memcpy(bytes, mData.data() + mPos, size);
        mPos += size;
        // The host is little endian (x86-64, ARM64); swap big-endian data.
        if (mFormat == PlyFormat::BinaryBig) std::reverse(bytes, bytes + size);
        switch (type) {
            case PlyType::Int8:
                return double(int8_t(bytes[0]));
            case PlyType::UInt8:
                return double(bytes[0]);
            case PlyType::Int16:
                return double(load<int16_t>(bytes));
            case PlyType::UInt16:
                return double(load<uint16_t>(bytes));
            case PlyType::Int32:
                return double(load<int32_t>(bytes));
            case PlyType::UInt32:
                return double(load<uint32_t>(bytes));
            case PlyType::Float32:
                return double(load<float>(bytes));
            case PlyType::Float64:
                return load<double>(bytes);
        }
        return 0.0;
    }

private:
    const std::string& mData;
    size_t mPos;
    PlyFormat mFormat;
    const std::string& mPath;

    template <class T>
    static T load(const unsigned char* bytes) {
        T v;
        std::memcpy(&v, bytes, sizeof(T));
        return v;
    }
    double readAscii() {
        while (mPos < mData.size() && std::isspace(static_cast<unsigned char>(mData[mPos]))) ++mPos;
        if (mPos >= mData.size())
            throw UserError(mPath + ": PLY file is truncated (ASCII data ends early)");
        const char* begin = mData.c_str() + mPos;
        char* end = nullptr;
        double v = std::strtod(begin, &end);
        if (end == begin) {
            size_t len = 0;
            while (begin[len] && !std::isspace(static_cast<unsigned char>(begin[len])) && len < 20)
                ++len;
            throw UserError(fmt::format("{}: PLY ASCII data: expected a number, got '{}'", mPath,
                                        std::string(begin, len)));
        }
        mPos += size_t(end - begin);
        return v;
    }
};

}  // namespace

Mesh readPly(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError(path + ": cannot open PLY file");
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

    // Header: line based, terminated by "end_header".
    size_t pos = 0;
    int lineNo = 0;
    auto nextLine = [&]() -> std::string {
        if (pos >= data.size()) throw UserError(path + ": PLY header has no end_header line");
        size_t end = data.find('\n', pos);
        if (end == std::string::npos) end = data.size();
        std::string line = data.substr(pos, end - pos);
        pos = std::min(end + 1, data.size());
        ++lineNo;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return line;
    };
    if (nextLine() != "ply") throw UserError(path + ": not a PLY file (first line is not 'ply')");
    PlyFormat format = PlyFormat::Ascii;
    bool haveFormat = false;
    std::vector<PlyElement> elements;
    while (true) {
        std::string line = nextLine();
        std::istringstream ss(line);
        std::string token;
        if (!(ss >> token) || token == "comment" || token == "obj_info") continue;
        auto bad = [&](const std::string& what) {
            return UserError(
                fmt::format("{}: PLY header line {}: {} in '{}'", path, lineNo, what, line));
        };
        if (token == "end_header") break;
        if (token == "format") {
            std::string f, version;
            ss >> f >> version;
            if (f == "ascii")
                format = PlyFormat::Ascii;
            else if (f == "binary_little_endian")
                format = PlyFormat::BinaryLittle;
            else if (f == "binary_big_endian")
                format = PlyFormat::BinaryBig;
            else
                throw bad("expected ascii, binary_little_endian or binary_big_endian");
            haveFormat = true;
        } else if (token == "element") {
            PlyElement e;
            if (!(ss >> e.name >> e.count)) throw bad("expected 'element <name> <count>'");
            elements.push_back(e);
        } else if (token == "property") {
            if (elements.empty()) throw bad("property before any element");
            PlyProperty p;
            std::string type;
            if (!(ss >> type)) throw bad("expected a property type");
            if (type == "list") {
                std::string countType, itemType;
                if (!(ss >> countType >> itemType >> p.name) ||
                    !parsePlyType(countType, p.countType) || !parsePlyType(itemType, p.type))
                    throw bad("expected 'property list <count type> <item type> <name>'");
                p.isList = true;
            } else if (!parsePlyType(type, p.type) || !(ss >> p.name)) {
                throw bad("unknown property type '" + type + "'");
            }
            elements.back().properties.push_back(p);
        } else {
            throw bad("unknown header keyword '" + token + "'");
        }
    }
    if (!haveFormat) throw UserError(path + ": PLY header has no format line");

    Mesh mesh;
    mesh.name = path;
    PlyBody body(data, pos, format, path);
    bool haveVertices = false;
    for (const PlyElement& e : elements) {
        if (e.name == "vertex") {
            // Attribute slot per property: 0-2 position, 3-5 normal, 6-7 uv, -1 skipped.
            std::vector<int> slot(e.properties.size(), -1);
            bool hasNormal = false, hasUv = false;
            for (size_t i = 0; i < e.properties.size(); ++i) {
                const std::string& n = e.properties[i].name;
                static const std::pair<const char*, int> kNames[] = {
                    {"x", 0},         {"y", 1},        {"z", 2},         {"nx", 3},
                    {"ny", 4},        {"nz", 5},       {"u", 6},         {"v", 7},
                    {"s", 6},         {"t", 7},        {"texture_u", 6}, {"texture_v", 7},
                    {"texture_s", 6}, {"texture_t", 7}};
                for (auto& [name, s] : kNames)
                    if (n == name && !e.properties[i].isList) slot[i] = s;
                hasNormal |= slot[i] >= 3 && slot[i] <= 5;
                hasUv |= slot[i] >= 6;
            }
            mesh.positions.resize(e.count);
            if (hasNormal) mesh.normals.resize(e.count);
            if (hasUv) mesh.uvs.resize(e.count);
            for (size_t v = 0; v < e.count; ++v) {
                float values[8] = {0, 0, 0, 0, 0, 0, 0, 0};
                for (size_t i = 0; i < e.properties.size(); ++i) {
                    const PlyProperty& p = e.properties[i];
                    if (p.isList) {
                        auto count = size_t(body.read(p.countType));
                        for (size_t k = 0; k < count; ++k) body.read(p.type);
                        continue;
                    }
                    double value = body.read(p.type);
                    if (slot[i] >= 0) values[slot[i]] = float(value);
                }
                mesh.positions[v] = {values[0], values[1], values[2]};
                if (hasNormal) mesh.normals[v] = {values[3], values[4], values[5]};
                if (hasUv) mesh.uvs[v] = {values[6], values[7]};
            }
            haveVertices = true;
        } else if (e.name == "face") {
            for (size_t f = 0; f < e.count; ++f)
                for (const PlyProperty& p : e.properties) {
                    if (!p.isList) {
                        body.read(p.type);
                        continue;
                    }
                    auto count = size_t(body.read(p.countType));
                    if (p.name != "vertex_indices" && p.name != "vertex_index") {
                        for (size_t k = 0; k < count; ++k) body.read(p.type);
                        continue;
                    }
                    std::vector<uint32_t> poly(count);
                    for (size_t k = 0; k < count; ++k) {
                        double idx = body.read(p.type);
                        if (idx < 0 || idx >= double(mesh.positions.size()) || !haveVertices)
                            throw UserError(fmt::format(
                                "{}: PLY face {} references vertex {} but the file has {} vertices",
                                path, f, idx, mesh.positions.size()));
                        poly[k] = uint32_t(idx);
                    }
                    // Polygons become triangle fans (as Mitsuba does).
                    for (size_t k = 2; k < count; ++k)
                        mesh.indices.push_back({poly[0], poly[k - 1], poly[k]});
                }
        } else {
            // Skip unknown elements (edges, materials, ...) value by value.
            for (size_t i = 0; i < e.count; ++i)
                for (const PlyProperty& p : e.properties) {
                    auto count = p.isList ? size_t(body.read(p.countType)) : 1;
                    for (size_t k = 0; k < count; ++k) body.read(p.type);
                }
        }
    }
    if (mesh.positions.empty()) throw UserError(path + ": PLY file has no vertex element");
    validateMesh(mesh, path);
    return mesh;
}

}  // namespace loom::scene
