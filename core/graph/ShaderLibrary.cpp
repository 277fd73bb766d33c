#include "core/graph/ShaderLibrary.h"

namespace loom {

std::shared_ptr<gpu::ComputePipeline> ShaderLibrary::pipeline(const std::string& path,
                                                              const ShaderDefines& defines) {
    auto shader = mCompiler.compile(path, defines);
    std::string key = shader->path + "|" + shader->key;
    auto it = mPipelines.find(key);
    if (it != mPipelines.end()) return it->second.second;
    auto p = mGpu.createPipeline(shader->spirv, shader->reflection, shader->path);
    mPipelines[key] = {shader, p};
    return p;
}

size_t ShaderLibrary::reloadChanged() {
    size_t n = mCompiler.reloadChanged();
    if (n) mPipelines.clear();
    return n;
}

}  // namespace loom
