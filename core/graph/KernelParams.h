#pragma once
// Parameters reach the GPU from their declaration. A kernel's parameter members — its
// push-constant block and/or a uniform block named `PassParams` (for more than the 128 bytes
// push constants guarantee) — are filled by name:
//   1. standard values: frameSize (uvec2), frameIndex, seed, historyReset, time;
//   2. every parameter the pass declared in reflect() whose name a member has: Int -> int or
//      uint, Float -> float, Bool -> uint or bool, Enum -> uint index of the choice (GLSL names
//      choices with the generated `<PARAM>_<CHOICE>` defines, see kernelDefines), VecN -> vecN;
//   3. values the pass computes itself, with set().
// dispatch() throws a UserError naming the pass and the member when a member was never set:
// a name that drifted between C++ and GLSL cannot silently read zero.
#include <set>
#include <string>
#include <vector>

#include "core/graph/Pass.h"

namespace loom {

class ExecuteContext;
class ShaderLibrary;

// The defines a pass's kernels are compiled with: `<PARAM>_<CHOICE>` = index for each enum
// parameter declared without a registered ShaderEnum (those are global, ShaderEnums.h).
ShaderDefines kernelDefines(const PassReflection& r);
// Compiles a kernel of `pass` with kernelDefines(pass.reflection()) under `extra`; throws a
// logic_error when a generated define collides with a registered shader enum's.
std::shared_ptr<gpu::ComputePipeline> compileKernel(const Pass& pass, ShaderLibrary& shaders,
                                                    const std::string& path,
                                                    const ShaderDefines& extra = {});

class KernelParams {
public:
    KernelParams(const Pass& pass, const gpu::ComputePipeline& pipeline, const ExecuteContext& ctx);
    bool has(const std::string& member) const;
    KernelParams& set(const std::string& member, float v);
    KernelParams& set(const std::string& member, int32_t v);
    KernelParams& set(const std::string& member, uint32_t v);
    KernelParams& set(const std::string& member, const float* v, uint32_t count);  // vecN
    KernelParams& setUints(const std::string& member, const uint32_t* v, uint32_t count);
    KernelParams& setInts(const std::string& member, const int32_t* v, uint32_t count);
    // Members nothing set (empty once complete).
    std::vector<std::string> unset() const;
    // Checks completeness, binds the uniform block (if any) into `bindings` and dispatches
    // enough groups for width x height x depth threads.
    void dispatch(ExecuteContext& ctx, gpu::Bindings& bindings, uint32_t width, uint32_t height = 1,
                  uint32_t depth = 1);

    // The same with a group count instead of a thread count.
    void dispatchGroups(ExecuteContext& ctx, gpu::Bindings& bindings, uint32_t groupsX,
                        uint32_t groupsY = 1, uint32_t groupsZ = 1);
    // The same with group counts a kernel wrote to args (gpu::CommandList::dispatchIndirect).
    void dispatchIndirect(ExecuteContext& ctx, gpu::Bindings& bindings, const gpu::Buffer& args,
                          uint64_t offset = 0);

    static constexpr const char* kUniformBlock = "PassParams";

private:
    struct Block {
        const std::vector<ReflectedMember>* members = nullptr;
        std::vector<uint8_t> bytes;
    };
    void write(const std::string& name, const char* base, uint32_t count, const void* data);
    void setDeclared(const ParamDesc& desc, const json& value);
    // Checks and uploads; returns the push constants to dispatch with.
    gpu::PushConstants prepare(ExecuteContext& ctx, gpu::Bindings& bindings);
    void checkBufferLayouts(const ExecuteContext& ctx, const gpu::Bindings& bindings) const;
    std::string mPass;
    const gpu::ComputePipeline* mPipeline;
    PassReflection mReflection;
    Block mPush, mUniform;
    std::set<std::string> mSet;
};

}  // namespace loom
