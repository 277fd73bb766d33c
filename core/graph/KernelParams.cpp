#include "core/graph/KernelParams.h"

#include <fmt/format.h>

#include <cstring>
#include <stdexcept>

#include "core/graph/RenderGraph.h"
#include "core/graph/ShaderLibrary.h"
#include "core/util/Error.h"

namespace loom {

ShaderDefines kernelDefines(const PassReflection& r) {
    ShaderDefines d;
    for (auto& p : r.params())
        if (p.type == ParamType::Enum && p.shaderEnum.empty())
            d.merge(enumDefines(upperSnakeCase(p.name), p.choices));
    return d;
}

std::shared_ptr<gpu::ComputePipeline> compileKernel(const Pass& pass, ShaderLibrary& shaders,
                                                    const std::string& path,
                                                    const ShaderDefines& extra) {
    ShaderDefines defines = kernelDefines(pass.reflection());
    ShaderDefines shared = ShaderEnumRegistry::instance().defines();
    for (auto& [k, v] : defines)
        if (shared.count(k))
            throw std::logic_error(fmt::format(
                "pass '{}': enum define {} is also a registered shader enum's; declare the "
                "parameter over shaderEnum() or rename it",
                pass.type(), k));
    for (auto& [k, v] : extra) defines[k] = v;
    return shaders.pipeline(path, defines);
}

KernelParams::KernelParams(const Pass& pass, const gpu::ComputePipeline& pipeline,
                           const ExecuteContext& ctx)
    : mPass(pass.name().empty() ? pass.type() : pass.name()),
      mPipeline(&pipeline),
      mReflection(pass.reflection()) {
    const ShaderReflection& refl = pipeline.reflection();
    if (refl.pushConstants) {
        mPush.members = &refl.pushConstants->members;
        mPush.bytes.assign(refl.pushConstants->size, 0);
    }
    if (const ReflectedBinding* ub = refl.find(kUniformBlock);
        ub && ub->kind == DescriptorKind::UniformBuffer) {
        mUniform.members = &ub->members;
        mUniform.bytes.assign(ub->blockSize, 0);
    }
    // 1. Standard values.
    uint32_t size[2] = {ctx.width(), ctx.height()};
    if (has("frameSize")) setUints("frameSize", size, 2);
    if (has("frameIndex")) set("frameIndex", uint32_t(ctx.frameIndex()));
    if (has("seed")) set("seed", ctx.seed());
    if (has("historyReset")) set("historyReset", uint32_t(ctx.historyReset()));
    if (has("time")) set("time", ctx.time());
    // 2. Declared parameters, by name.
    for (auto& desc : mReflection.params())
        if (has(desc.name)) setDeclared(desc, pass.getParam(desc.name));
}

bool KernelParams::has(const std::string& member) const {
    for (const Block* b : {&mPush, &mUniform})
        if (b->members)
            for (auto& m : *b->members)
                if (m.name == member) return true;
    return false;
}

void KernelParams::write(const std::string& name, const char* baseIn, uint32_t count,
                         const void* data) {
    std::string base = baseIn;
    std::string expected = base;
    if (count > 1)
        expected = std::string(base == "int"    ? "i"
                               : base == "uint" ? "u"
                                                : "") +
                   "vec" + std::to_string(count);
    for (Block* b : {&mPush, &mUniform}) {
        if (!b->members) continue;
        for (auto& m : *b->members) {
            if (m.name != name) continue;
            if (m.type != expected && !(m.type == "bool" && expected == "uint"))
                throw UserError(
                    fmt::format("pass '{}', kernel '{}': parameter member '{}' is {} "
                                "but is set as {}",
                                mPass, mPipeline->name(), name, m.type, expected));
            std::memcpy(b->bytes.data() + m.offset, data, 4 * count);
            mSet.insert(name);
            return;
        }
    }
    throw UserError(fmt::format("pass '{}', kernel '{}' has no parameter member '{}'", mPass,
                                mPipeline->name(), name));
}

void KernelParams::setDeclared(const ParamDesc& desc, const json& value) {
    std::string type;
    for (const Block* b : {&mPush, &mUniform})
        if (b->members)
            for (auto& m : *b->members)
                if (m.name == desc.name) type = m.type;
    switch (desc.type) {
        case ParamType::Bool:
            set(desc.name, uint32_t(value.get<bool>()));
            break;
        case ParamType::Int:
            if (type == "uint")
                set(desc.name, uint32_t(value.get<int64_t>()));
            else
                set(desc.name, int32_t(value.get<int64_t>()));
            break;
        case ParamType::Float:
            set(desc.name, value.get<float>());
            break;
        case ParamType::Enum: {
            auto s = value.get<std::string>();
            uint32_t index = 0;
            while (index < desc.choices.size() && desc.choices[index] != s) ++index;
            set(desc.name, index);
            break;
        }
        case ParamType::Vec2:
        case ParamType::Vec3:
        case ParamType::Vec4: {
            std::vector<float> v = value.get<std::vector<float>>();
            set(desc.name, v.data(), uint32_t(v.size()));
            break;
        }
        default:
            throw UserError(
                fmt::format("pass '{}': parameter '{}' ({}) cannot reach a kernel "
                            "member; rename the member or set it explicitly",
                            mPass, desc.name, paramTypeName(desc.type)));
    }
}

KernelParams& KernelParams::set(const std::string& m, float v) {
    write(m, "float", 1, &v);
    return *this;
}
KernelParams& KernelParams::set(const std::string& m, int32_t v) {
    write(m, "int", 1, &v);
    return *this;
}
KernelParams& KernelParams::set(const std::string& m, uint32_t v) {
    write(m, "uint", 1, &v);
    return *this;
}
KernelParams& KernelParams::set(const std::string& m, const float* v, uint32_t count) {
    write(m, "float", count, v);
    return *this;
}
KernelParams& KernelParams::setUints(const std::string& m, const uint32_t* v, uint32_t count) {
    write(m, "uint", count, v);
    return *this;
}
KernelParams& KernelParams::setInts(const std::string& m, const int32_t* v, uint32_t count) {
    write(m, "int", count, v);
    return *this;
}

std::vector<std::string> KernelParams::unset() const {
    std::vector<std::string> out;
    for (const Block* b : {&mPush, &mUniform})
        if (b->members)
            for (auto& m : *b->members)
                if (!m.name.empty() && !mSet.count(m.name)) out.push_back(m.name);
    return out;
}

// A buffer port's declared per-pixel element and header sizes must be the kernel's runtime
// array stride and offset (a C++ constant restating a GLSL struct size cannot drift).
void KernelParams::checkBufferLayouts(const ExecuteContext& ctx,
                                      const gpu::Bindings& bindings) const {
    for (auto& [name, res] : bindings.entries()) {
        auto* buf = std::get_if<std::shared_ptr<gpu::Buffer>>(&res);
        const ReflectedBinding* rb = mPipeline->reflection().find(name);
        if (!buf || !*buf || !rb || rb->runtimeArrayStride == 0) continue;
        std::string port = ctx.portOf(buf->get());
        const PortDesc* desc = mReflection.findPort(port);
        if (!desc || desc->size.mode != SizeRule::Mode::Frame || desc->size.bytesPerPixel == 0)
            continue;
        if (desc->size.bytesPerPixel != rb->runtimeArrayStride ||
            desc->size.extraBytes != rb->runtimeArrayOffset)
            throw UserError(fmt::format(
                "pass '{}': port '{}' declares {} header bytes + {} bytes per pixel, but kernel "
                "'{}' reads '{}' as {} header bytes + an array of {}-byte elements",
                mPass, port, desc->size.extraBytes, desc->size.bytesPerPixel, mPipeline->name(),
                name, rb->runtimeArrayOffset, rb->runtimeArrayStride));
    }
}

gpu::PushConstants KernelParams::prepare(ExecuteContext& ctx, gpu::Bindings& bindings) {
    auto missing = unset();
    if (!missing.empty()) {
        std::string list;
        for (auto& m : missing) list += (list.empty() ? "" : ", ") + m;
        throw UserError(fmt::format(
            "pass '{}', kernel '{}': parameter member(s) {} are set by nothing (no declared "
            "parameter, standard value or set() of that name)",
            mPass, mPipeline->name(), list));
    }
    checkBufferLayouts(ctx, bindings);
    if (mUniform.members) {
        // One small host-visible buffer per dispatch, alive until the command list completes.
        auto ub = ctx.gpu().createBuffer(std::max<size_t>(mUniform.bytes.size(), 16),
                                         mPass + ".PassParams", true);
        std::memcpy(ub->mapped(), mUniform.bytes.data(), mUniform.bytes.size());
        ctx.cmd().retain(ub);
        bindings.set(kUniformBlock, ub);
    }
    gpu::PushConstants pc(*mPipeline);
    if (!mPush.bytes.empty()) pc.setBytes(mPush.bytes);
    return pc;
}

void KernelParams::dispatch(ExecuteContext& ctx, gpu::Bindings& bindings, uint32_t width,
                            uint32_t height, uint32_t depth) {
    gpu::PushConstants pc = prepare(ctx, bindings);
    ctx.cmd().dispatchThreads(*mPipeline, bindings, mPush.members ? &pc : nullptr, width, height,
                              depth);
}

void KernelParams::dispatchGroups(ExecuteContext& ctx, gpu::Bindings& bindings, uint32_t x,
                                  uint32_t y, uint32_t z) {
    gpu::PushConstants pc = prepare(ctx, bindings);
    ctx.cmd().dispatch(*mPipeline, bindings, mPush.members ? &pc : nullptr, x, y, z);
}

void KernelParams::dispatchIndirect(ExecuteContext& ctx, gpu::Bindings& bindings,
                                    const gpu::Buffer& args, uint64_t offset) {
    gpu::PushConstants pc = prepare(ctx, bindings);
    ctx.cmd().dispatchIndirect(*mPipeline, bindings, mPush.members ? &pc : nullptr, args, offset);
}
}  // namespace loom
