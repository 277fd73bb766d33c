#include "core/graph/ShaderLibrary.h"

#include <algorithm>

#include "core/util/Log.h"

namespace loom {

namespace {

std::string lastGoodKey(const std::string& resolved, const ShaderDefines& defines) {
    std::string key = resolved;
    for (const auto& [k, v] : defines) key += "|" + k + "=" + v;
    return key;
}

}  // namespace

std::shared_ptr<gpu::ComputePipeline> ShaderLibrary::pipeline(const std::string& path,
                                                              const ShaderDefines& defines) {
    std::shared_ptr<const CompiledShader> shader;
    try {
        shader = mCompiler.compile(path, defines);
    } catch (const ShaderCompileError& e) {
        if (!mKeepLastGood) throw;
        auto it = mLastGood.find(lastGoodKey(mCompiler.resolve(path), defines));
        if (it == mLastGood.end()) throw;  // never compiled: nothing to fall back to
        // Remember which sources failed so reloadChanged() notices when they are fixed.
        it->second.failedKey = mCompiler.cacheKey(it->second.path, defines);
        // Passes may ask for the same pipeline more than once: report each error once.
        if (std::find(mErrors.begin(), mErrors.end(), e.what()) == mErrors.end()) {
            logWarning("{}; keeping the last good version", e.what());
            mErrors.push_back(e.what());
        }
        return it->second.pipeline;
    }
    std::string key = shader->path + "|" + shader->key;
    auto it = mPipelines.find(key);
    std::shared_ptr<gpu::ComputePipeline> p;
    if (it != mPipelines.end()) {
        p = it->second.second;
    } else {
        p = mGpu.createPipeline(shader->spirv, shader->reflection, shader->path);
        mPipelines[key] = {shader, p};
    }
    if (mKeepLastGood)
        mLastGood[lastGoodKey(shader->path, defines)] = {shader->path, defines, p, ""};
    return p;
}

size_t ShaderLibrary::reloadChanged() {
    size_t n = mCompiler.reloadChanged();
    // Failed shaders left the compiler's memory; watch their files here.
    for (auto& [key, good] : mLastGood) {
        if (good.failedKey.empty()) continue;
        try {
            if (mCompiler.cacheKey(good.path, good.defines) == good.failedKey) continue;
        } catch (const UserError&) {
            continue;  // an include vanished: still broken
        }
        good.failedKey.clear();
        ++n;
    }
    if (n) mPipelines.clear();
    return n;
}

std::vector<std::string> ShaderLibrary::takeErrors() {
    std::vector<std::string> out;
    out.swap(mErrors);
    return out;
}

}  // namespace loom
