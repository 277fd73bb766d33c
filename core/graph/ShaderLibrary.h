#pragma once
// Compiled pipelines by (shader path, defines), on top of ShaderCompiler's SPIR-V cache.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/gpu/Context.h"
#include "core/shader/ShaderCompiler.h"

namespace loom {

class ShaderLibrary {
public:
    ShaderLibrary(gpu::Context& gpu, ShaderCompiler& compiler) : mGpu(gpu), mCompiler(compiler) {}
    std::shared_ptr<gpu::ComputePipeline> pipeline(const std::string& path,
                                                   const ShaderDefines& defines = {});
    // Drops pipelines whose sources changed; returns how many (the graph recompiles passes).
    // Shaders kept at their last good version (see setKeepLastGood) count once their files
    // change again.
    size_t reloadChanged();
    ShaderCompiler& compiler() { return mCompiler; }
    gpu::Context& gpu() { return mGpu; }

    // Hot reload (inspector): when a shader that compiled before fails to compile, pipeline()
    // returns its last good version and records the error instead of throwing.
    void setKeepLastGood(bool keep) { mKeepLastGood = keep; }
    // Compile errors kept back (last good version used) since the last call; clears them.
    std::vector<std::string> takeErrors();

private:
    gpu::Context& mGpu;
    ShaderCompiler& mCompiler;
    std::map<std::string, std::pair<std::shared_ptr<const CompiledShader>,
                                    std::shared_ptr<gpu::ComputePipeline>>>
        mPipelines;
    struct LastGood {
        std::string path;  // resolved
        ShaderDefines defines;
        std::shared_ptr<gpu::ComputePipeline> pipeline;
        std::string failedKey;  // cache key of the sources that failed; "" = compiles
    };
    std::map<std::string, LastGood> mLastGood;  // by resolved path + defines
    bool mKeepLastGood = false;
    std::vector<std::string> mErrors;
};

}  // namespace loom
