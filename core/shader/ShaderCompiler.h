#pragma once
// Run-time GLSL -> SPIR-V through glslang: #include with search paths, defines
// (permutations), errors with file:line and the offending source line, and an on-disk
// SPIR-V cache keyed by the text of every included file + defines + compiler version.
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/shader/SpirvReflect.h"
#include "core/util/Error.h"

namespace loom {

using ShaderDefines = std::map<std::string, std::string>;

class ShaderCompileError : public UserError {
public:
    using UserError::UserError;
};

struct CompiledShader {
    std::string path;  // resolved main file
    ShaderDefines defines;
    std::vector<uint32_t> spirv;
    ShaderReflection reflection;
    std::vector<std::string> sources;  // main file + every file it (transitively) includes
    std::string key;                   // cache key (hex)
    bool fromDiskCache = false;
};

class ShaderCompiler {
public:
    // cacheDir "" disables the disk cache.
    ShaderCompiler(std::vector<std::string> searchPaths, std::string cacheDir);

    void addSearchPath(const std::string& dir);
    const std::vector<std::string>& searchPaths() const { return mSearchPaths; }
    // Finds a shader: absolute, relative to fromDir, then each search path. Throws UserError.
    std::string resolve(const std::string& path, const std::string& fromDir = "") const;

    // Defines added to every compile, under each shader's own (which win). The constructor
    // takes them from $LOOM_SHADER_DEFINES ("NAME=VALUE;NAME2"), so a test or a user can put a
    // deliberate change (e.g. a bias) into every kernel without editing a pass.
    void setGlobalDefines(ShaderDefines defines) { mGlobalDefines = std::move(defines); }
    const ShaderDefines& globalDefines() const { return mGlobalDefines; }

    // Compiles (or loads from the in-memory / disk cache). Throws ShaderCompileError.
    std::shared_ptr<const CompiledShader> compile(const std::string& path,
                                                  const ShaderDefines& defines = {});
    // Cache key for a shader without compiling it (reads every included file).
    std::string cacheKey(const std::string& resolvedPath, const ShaderDefines& defines,
                         std::vector<std::string>* sources = nullptr) const;

    // Hot reload: drops in-memory results whose source files changed on disk. Returns how
    // many were dropped; generation() increases when any were.
    size_t reloadChanged();
    uint64_t generation() const { return mGeneration; }

    struct Stats {
        uint64_t compiles = 0, diskHits = 0, memoryHits = 0;
    };
    Stats stats() const { return mStats; }

private:
    std::vector<std::string> mSearchPaths;
    std::string mCacheDir;
    ShaderDefines mGlobalDefines;
    std::map<std::string, std::shared_ptr<const CompiledShader>> mMemory;  // by path+defines
    uint64_t mGeneration = 0;
    Stats mStats;
    mutable std::mutex mMutex;
};

// "NAME=VALUE;NAME2;..." (a bare NAME is NAME=1). Throws UserError naming a malformed item.
ShaderDefines parseShaderDefines(const std::string& text);

// Source-level version of this compiler front end, part of every cache key.
std::string shaderCompilerVersion();

}  // namespace loom
