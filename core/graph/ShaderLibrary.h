#pragma once
// Compiled pipelines by (shader path, defines), on top of ShaderCompiler's SPIR-V cache.
#include <map>
#include <memory>
#include <string>

#include "core/gpu/Context.h"
#include "core/shader/ShaderCompiler.h"

namespace loom {

class ShaderLibrary {
public:
    ShaderLibrary(gpu::Context& gpu, ShaderCompiler& compiler) : mGpu(gpu), mCompiler(compiler) {}
    std::shared_ptr<gpu::ComputePipeline> pipeline(const std::string& path,
                                                   const ShaderDefines& defines = {});
    // Drops pipelines whose sources changed; returns how many (the graph recompiles passes).
    size_t reloadChanged();
    ShaderCompiler& compiler() { return mCompiler; }
    gpu::Context& gpu() { return mGpu; }

private:
    gpu::Context& mGpu;
    ShaderCompiler& mCompiler;
    std::map<std::string, std::pair<std::shared_ptr<const CompiledShader>,
                                    std::shared_ptr<gpu::ComputePipeline>>>
        mPipelines;
};

}  // namespace loom
