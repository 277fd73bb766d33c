#pragma once
// Lua 5.4 scripting: the `loom` module (renderers, parameters, graph editing, cameras, images,
// metrics, CSV/JSON/plots, progress, sharded sweeps) and the `loom run` driver. The Lua API is
// documented in scripts/README.md.
//
// Every C function of the module runs its C++ body inside try/catch; an exception's message is
// copied into a fixed buffer, C++ scope is left, and only then lua_error() raises it, so a Lua
// error never unwinds (longjmps) through C++ frames and a script cannot crash the process.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace loom::gpu {
class Context;
}

namespace loom::script {

class LuaRuntime {
public:
    struct Options {
        std::vector<std::string> args;  // loom.args (script arguments)
        uint32_t shardIndex = 0;        // --shard I/N: this process owns sweep values
        uint32_t shardCount = 1;        // I, I+N, I+2N, ... (0-based)
        // With shardCount > 1, loom.write_csv(P) writes P's part DIR/STEM.PART-I.csv, tagged
        // with this id (loom merge refuses parts of different sweeps; "" = "unnamed").
        std::string sweepId;
        // A sweep job's directory (loom sweep-submit): each shard lists the CSV files it wrote
        // in DIR/parts/task-I.txt, for the merge job.
        std::string sweepDir;
        // loom.phase: "run", or "merge" when a sweep's merge job runs the script again for its
        // plot step (loom.sweep then yields no values).
        std::string phase = "run";
        // Context for renderers on the default device ("" = LOOM_DEVICE, else lavapipe); tests
        // pass theirs. Others are created on first use and shared by every renderer.
        std::shared_ptr<gpu::Context> gpu;
        std::string cacheDir;     // shader/pipeline cache ("" = the context's default)
        bool printErrors = true;  // print Lua errors (message + traceback) to stderr
    };
    explicit LuaRuntime(Options options);
    ~LuaRuntime();
    LuaRuntime(const LuaRuntime&) = delete;
    LuaRuntime& operator=(const LuaRuntime&) = delete;

    // Runs a script file. Returns 0, the integer the script returns, or 2 on any Lua error
    // (syntax or runtime: "script:line: message" and a traceback, kept in lastError()).
    int runFile(const std::string& path);
    // Runs Lua source text; chunkName names it in messages ("=name" shows as "name").
    int runString(const std::string& code, const std::string& chunkName = "=script");
    // The last error message with its traceback ("" after a successful run).
    const std::string& lastError() const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

// Parses "I/N" (0 <= I < N); throws UserError naming the expected form.
void parseShard(const std::string& text, uint32_t& index, uint32_t& count);

}  // namespace loom::script
