#include "core/shader/ShaderCompiler.h"
#include "core/shader/ShaderEnums.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>
#include <glslang/build_info.h>

#include <unistd.h>
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "core/util/Hash.h"
#include "core/util/Log.h"

namespace loom {

namespace fs = std::filesystem;

namespace {

// Bump when the way sources are prepared changes, so old cache entries are ignored.
constexpr const char* kFrontEndRevision = "loom-shader-2";

bool readFile(const std::string& path, std::string& out) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    std::stringstream ss;
    ss << in.rdbuf();
    out = ss.str();
    return true;
}

void initGlslang() {
    static std::once_flag once;
    std::call_once(once, [] {
        glslang::InitializeProcess();
        std::atexit([] { glslang::FinalizeProcess(); });
    });
}

// Inserts the include extension right after #version and restores line numbers with #line.
std::string prepareSource(const std::string& text, const std::string& path) {
    std::istringstream in(text);
    std::string line, out;
    int lineNo = 0;
    bool inserted = false;
    while (std::getline(in, line)) {
        ++lineNo;
        out += line + "\n";
        if (!inserted && line.rfind("#version", 0) == 0) {
            out += "#extension GL_GOOGLE_include_directive : require\n";
            out += "#line " + std::to_string(lineNo + 1) + " \"" + path + "\"\n";
            inserted = true;
        }
    }
    if (!inserted)
        throw ShaderCompileError(path +
                                 ":1: error: shader has no #version line (use #version 460)");
    return out;
}

// glslang's automatic binding assignment only maps resources the shader uses; a declared but
// unused one keeps binding 0 and collides with a used one (an invalid descriptor set layout
// whose writes go nowhere). Resources are bound by name, so give every Binding decoration
// its own number, in declaration order.
void assignUniqueBindings(std::vector<uint32_t>& spirv) {
    constexpr uint32_t kOpDecorate = 71, kDecorationBinding = 33;
    uint32_t next = 0;
    for (size_t i = 5; i < spirv.size();) {
        uint32_t words = spirv[i] >> 16, opcode = spirv[i] & 0xffffu;
        if (words == 0) break;  // malformed; reflection reports it
        if (opcode == kOpDecorate && words >= 4 && i + 3 < spirv.size() &&
            spirv[i + 2] == kDecorationBinding)
            spirv[i + 3] = next++;
        i += words;
    }
}

// Finds #include "x" / <x> lines; conditionals are ignored (the key may over-include, which
// only costs an extra file read). `system` marks <x>, which the includer resolves from the
// search paths only (not next to the including file).
struct IncludeLine {
    std::string header;
    bool system = false;
};
std::vector<IncludeLine> scanIncludes(const std::string& text) {
    static const std::regex re(R"(^\s*#\s*include\s*([<"])([^>"]+)[>"])");
    std::vector<IncludeLine> out;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        std::smatch m;
        if (std::regex_search(line, m, re)) out.push_back({m[2], m[1] == "<"});
    }
    return out;
}

std::string defineString(const ShaderDefines& defines) {
    std::string s;
    for (const auto& [k, v] : defines) s += "#define " + k + " " + v + "\n";
    return s;
}

std::string memoryKey(const std::string& path, const ShaderDefines& defines) {
    return path + "\n" + defineString(defines);
}

class Includer : public glslang::TShader::Includer {
public:
    Includer(const ShaderCompiler& compiler, std::vector<std::string>& sources)
        : mCompiler(compiler), mSources(sources) {}

    IncludeResult* includeLocal(const char* header, const char* includer, size_t) override {
        return load(header, fs::path(includer).parent_path().string());
    }
    IncludeResult* includeSystem(const char* header, const char*, size_t) override {
        return load(header, "");
    }
    void releaseInclude(IncludeResult* r) override {
        if (!r) return;
        delete static_cast<std::string*>(r->userData);
        delete r;
    }

private:
    IncludeResult* load(const std::string& header, const std::string& fromDir) {
        std::string path;
        try {
            path = mCompiler.resolve(header, fromDir);
        } catch (const UserError&) {
            return nullptr;  // glslang reports "cannot find include" with file:line
        }
        auto* text = new std::string();
        readFile(path, *text);
        if (std::find(mSources.begin(), mSources.end(), path) == mSources.end())
            mSources.push_back(path);
        return new IncludeResult(path, text->data(), text->size(), text);
    }
    const ShaderCompiler& mCompiler;
    std::vector<std::string>& mSources;
};

// Turns glslang's log into "file:line: error: msg" plus the offending source line.
std::string formatLog(const std::string& log) {
    static const std::regex re(R"(^(ERROR|WARNING): (.+?):(\d+): (.*)$)");
    std::istringstream in(log);
    std::string line, out;
    while (std::getline(in, line)) {
        std::smatch m;
        if (std::regex_match(line, m, re)) {
            std::string file = m[2], msg = m[4];
            int lineNo = std::stoi(m[3]);
            std::string kind = m[1] == "ERROR" ? "error" : "warning";
            out += file + ":" + std::to_string(lineNo) + ": " + kind + ": " + msg + "\n";
            std::string text;
            if (readFile(file, text)) {
                std::istringstream src(text);
                std::string s;
                for (int i = 0; i < lineNo && std::getline(src, s); ++i) {
                }
                if (!s.empty()) out += "    " + s + "\n";
            }
        } else if (!line.empty() && line.find("compilation errors") == std::string::npos) {
            out += line + "\n";
        }
    }
    while (!out.empty() && out.back() == '\n') out.pop_back();
    return out;
}

}  // namespace

std::string shaderCompilerVersion() {
    return fmt::format("{} glslang-{}.{}.{}", kFrontEndRevision, GLSLANG_VERSION_MAJOR,
                       GLSLANG_VERSION_MINOR, GLSLANG_VERSION_PATCH);
}

ShaderCompiler::ShaderCompiler(std::vector<std::string> searchPaths, std::string cacheDir)
    : mSearchPaths(std::move(searchPaths)), mCacheDir(std::move(cacheDir)) {
    if (const char* env = std::getenv("LOOM_SHADER_DEFINES"))
        mGlobalDefines = parseShaderDefines(env);
}

ShaderDefines parseShaderDefines(const std::string& text) {
    ShaderDefines out;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ';')) {
        if (item.find_first_not_of(" \t") == std::string::npos) continue;
        auto eq = item.find('=');
        std::string name = item.substr(0, eq),
                    value = eq == std::string::npos ? "1" : item.substr(eq + 1);
        static const std::regex ident(R"(\s*([A-Za-z_][A-Za-z0-9_]*)\s*)");
        std::smatch m;
        if (!std::regex_match(name, m, ident))
            throw UserError("LOOM_SHADER_DEFINES: '" + item + "' is not NAME or NAME=VALUE");
        out[m[1]] = value;
    }
    return out;
}

void ShaderCompiler::addSearchPath(const std::string& dir) {
    std::lock_guard lock(mMutex);
    mSearchPaths.push_back(dir);
}

std::string ShaderCompiler::resolve(const std::string& path, const std::string& fromDir) const {
    std::vector<fs::path> candidates;
    if (fs::path(path).is_absolute()) {
        candidates.push_back(path);
    } else {
        if (!fromDir.empty()) candidates.push_back(fs::path(fromDir) / path);
        for (const auto& dir : mSearchPaths) candidates.push_back(fs::path(dir) / path);
        candidates.push_back(path);
    }
    for (const auto& c : candidates) {
        std::error_code ec;
        if (fs::is_regular_file(c, ec)) return fs::weakly_canonical(c, ec).string();
    }
    std::string searched;
    for (const auto& c : candidates) searched += "\n  " + c.string();
    throw UserError("shader file '" + path + "' not found; looked in:" + searched);
}

std::string ShaderCompiler::cacheKey(const std::string& resolvedPath, const ShaderDefines& defines,
                                     std::vector<std::string>* sourcesOut) const {
    Hasher h;
    h.add(shaderCompilerVersion()).add(defineString(defines)).add(resolvedPath);
    std::vector<std::string> queue{resolvedPath}, seen;
    while (!queue.empty()) {
        std::string p = queue.back();
        queue.pop_back();
        if (std::find(seen.begin(), seen.end(), p) != seen.end()) continue;
        seen.push_back(p);
        std::string text;
        if (!readFile(p, text)) {
            h.add("<missing>" + p);
            continue;
        }
        h.add(p).add(text);
        for (const auto& inc : scanIncludes(text)) {
            // Resolve exactly as the Includer does, or the key tracks the wrong file.
            try {
                queue.push_back(
                    resolve(inc.header, inc.system ? "" : fs::path(p).parent_path().string()));
            } catch (const UserError&) {
                h.add("<unresolved>" + inc.header);
            }
        }
    }
    if (sourcesOut) *sourcesOut = seen;
    return h.hex();
}

std::shared_ptr<const CompiledShader> ShaderCompiler::compile(const std::string& pathIn,
                                                              const ShaderDefines& localDefines) {
    std::string path = resolve(pathIn);
    // Registered shader enums, then global defines (LOOM_SHADER_DEFINES), then the shader's
    // own: all part of every key.
    ShaderDefines defines = ShaderEnumRegistry::instance().defines();
    for (const auto& [k, v] : mGlobalDefines) defines[k] = v;
    for (const auto& [k, v] : localDefines) defines[k] = v;
    std::string mkey = memoryKey(path, defines);
    {
        std::lock_guard lock(mMutex);
        if (auto it = mMemory.find(mkey); it != mMemory.end()) {
            ++mStats.memoryHits;
            return it->second;
        }
    }

    auto result = std::make_shared<CompiledShader>();
    result->path = path;
    result->defines = defines;
    result->key = cacheKey(path, defines, &result->sources);

    // Disk cache: SPIR-V words; reflection is recomputed (cheap) from them.
    std::string cacheFile = mCacheDir.empty() ? "" : mCacheDir + "/spirv/" + result->key + ".spv";
    if (!cacheFile.empty()) {
        std::string bytes;
        if (readFile(cacheFile, bytes) && bytes.size() % 4 == 0 && bytes.size() >= 20) {
            result->spirv.resize(bytes.size() / 4);
            std::memcpy(result->spirv.data(), bytes.data(), bytes.size());
            try {
                result->reflection = reflectSpirv(result->spirv);
                result->fromDiskCache = true;
            } catch (const std::exception&) {
                result->spirv.clear();  // corrupt entry: recompile
            }
        }
    }

    if (!result->fromDiskCache) {
        initGlslang();
        std::string text;
        if (!readFile(path, text)) throw UserError("cannot read shader '" + path + "'");
        std::string prepared = prepareSource(text, path);
        std::string preamble = defineString(defines);

        glslang::TShader shader(EShLangCompute);
        const char* strings[] = {prepared.c_str()};
        const int lengths[] = {int(prepared.size())};
        const char* names[] = {path.c_str()};
        shader.setStringsWithLengthsAndNames(strings, lengths, names, 1);
        shader.setPreamble(preamble.c_str());
        shader.setEnvInput(glslang::EShSourceGlsl, EShLangCompute, glslang::EShClientVulkan, 100);
        shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_2);
        shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_5);
        // Bindings are assigned by the compiler and looked up by name from the reflection.
        shader.setAutoMapBindings(true);
        shader.setAutoMapLocations(true);
        std::vector<std::string> includedSources;
        Includer includer(*this, includedSources);
        auto messages = EShMessages(EShMsgSpvRules | EShMsgVulkanRules);
        if (!shader.parse(GetDefaultResources(), 460, false, messages, includer))
            throw ShaderCompileError(formatLog(shader.getInfoLog()));
        glslang::TProgram program;
        program.addShader(&shader);
        if (!program.link(messages) || !program.mapIO())
            throw ShaderCompileError(path + ": link error:\n" + formatLog(program.getInfoLog()));
        ::spv::SpvBuildLogger logger;
        glslang::SpvOptions options;
        options.disableOptimizer = true;  // the driver optimises; keeps compile time low
        glslang::GlslangToSpv(*program.getIntermediate(EShLangCompute), result->spirv, &logger,
                              &options);
        assignUniqueBindings(result->spirv);
        result->reflection = reflectSpirv(result->spirv);
        ++mStats.compiles;
        if (!cacheFile.empty()) {
            std::error_code ec;
            fs::create_directories(fs::path(cacheFile).parent_path(), ec);
            std::string tmp = cacheFile + ".tmp" + std::to_string(::getpid());
            {
                std::ofstream out(tmp, std::ios::binary);
                out.write(reinterpret_cast<const char*>(result->spirv.data()),
                          std::streamsize(result->spirv.size() * 4));
            }
            fs::rename(tmp, cacheFile, ec);
        }
        logDebug("compiled shader {} ({} words)", path, result->spirv.size());
    } else {
        ++mStats.diskHits;
    }

    std::lock_guard lock(mMutex);
    mMemory[mkey] = result;
    return result;
}

size_t ShaderCompiler::reloadChanged() {
    std::lock_guard lock(mMutex);
    size_t dropped = 0;
    for (auto it = mMemory.begin(); it != mMemory.end();) {
        if (cacheKey(it->second->path, it->second->defines) != it->second->key) {
            logInfo("shader changed, reloading: {}", it->second->path);
            it = mMemory.erase(it);
            ++dropped;
        } else {
            ++it;
        }
    }
    if (dropped) ++mGeneration;
    return dropped;
}

}  // namespace loom
