// loom: command-line front end. Usage and input errors exit 2 with one clear message;
// internal errors exit 1.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "apps/CliArgs.h"
#include "apps/loom/PassDocs.h"
#include "apps/loom/Sweep.h"
#include "core/graph/Renderer.h"
#include "core/script/Csv.h"
#include "core/script/LuaBindings.h"
#include "core/util/Log.h"

using namespace loom;

namespace {

using cli::parseUint;
using cli::UsageError;

// The marked output --out writes: the first one, except that an HDR file (.exr, .hdr, .pfm)
// gets the first linear one (not a ToneMap pass's display image), named in the log.
std::string portForOut(RenderGraph& graph, const std::string& file) {
    std::string ext = std::filesystem::path(file).extension().string();
    for (auto& c : ext) c = char(std::tolower(c));
    const auto& marked = graph.outputs();
    if (ext != ".exr" && ext != ".hdr" && ext != ".pfm") return marked.front();
    std::string list;
    for (const auto& port : marked) {
        std::string pass = port.substr(0, port.find('.'));
        for (auto& p : graph.passes())
            if (p->name() == pass && p->type() != "ToneMap") {
                if (port != marked.front())
                    logInfo(
                        "--out {}: writing the linear output {} (the first marked output, {}, "
                        "is tone-mapped)",
                        file, port, marked.front());
                return port;
            }
        list += (list.empty() ? "" : ", ") + port;
    }
    throw UsageError("--out " + file +
                     ": an HDR file needs linear radiance, but every marked "
                     "output of graph '" +
                     graph.name() + "' is tone-mapped (" + list +
                     "); write one with --output PASS.PORT=" + file + " or use .png");
}

const char* kMainHelp = R"(loom - research rendering framework (render graphs on Vulkan compute)

usage: loom <command> [options]

commands:
  render GRAPH     render frames of a graph and write images
  validate GRAPH   check graph files without rendering
  passes           list every pass type with ports and parameters
  devices          list Vulkan devices
  run SCRIPT.lua   run a Lua script (captures, sweeps, equal-time comparisons, plots)
  merge OUT PARTS  merge the CSV files of sharded 'loom run --shard' runs
  sweep-submit     submit a sweep to Slurm: a job array of shards and a merge job

'loom <command> --help' describes each command.
)";

const char* kRenderHelp = R"(usage: loom render GRAPH [options]

  --scene FILE              scene (.json Loom, .xml Mitsuba 0.5-3, .gltf/.glb, .obj)
  --define NAME=VALUE       Mitsuba scene variable ($NAME), like mitsuba -D (repeatable)
  --width W, --height H     frame size (default 256 x 256)
  --frames N                frames to render (default 1)
  --seed K                  random seed (default 0); same seed, same image
  --device D                device index or name (default: LOOM_DEVICE, else lavapipe)
  --out FILE                write the first marked output (.png/.jpg), or for .exr/.hdr
                            the first linear one (not a ToneMap display image)
  --output PASS.PORT=FILE   write a marked output (repeatable)
  --set PASS.PARAM=VALUE    set a parameter; VALUE is JSON (1.5, true, [1,2]) or a string
  --check-nan               fail if any float output holds NaN or Inf
  --timings                 print per-pass GPU times averaged over the frames (the first,
                            warm-up frame excluded when there are several), then the
                            memory of every graph resource (kind, size, lifetime, aliasing)
  --validation              enable Vulkan validation layers
  --gpu-timeout S           GPU watchdog: a frame that has not finished after S seconds
                            (default 600, or LOOM_GPU_TIMEOUT; 0 = wait forever) ends the
                            run with exit code 2, naming the pass that was running
  --quiet                   print only errors (and the --timings table)

Without --out/--output the first marked output goes to out/<graph name>.png.
)";

const char* kValidateHelp = R"(usage: loom validate GRAPH [GRAPH ...]

Loads each graph, checks passes, parameters, edges, formats, cycles and outputs, compiles it
(cull, order, allocate) at 256x256, and compiles every pass's shaders on the default device
(lavapipe, on the CPU), so a ComputePass whose shader is missing or does not compile fails here.
Prints OK or the first error per file.
)";

const char* kPassesHelp = R"(usage: loom passes [--json | --markdown TYPE]
       loom passes --update-docs FILE... | --check-docs FILE...

Lists every registered pass type with its ports and parameters (type, default, range, doc).
--markdown prints one type's tables; --update-docs rewrites the blocks between
'<!-- loom passes TYPE -->' and '<!-- /loom passes -->' in each file with those tables, and
--check-docs exits 2 naming each block that differs (the READMEs' tables are generated).
)";

const char* kDevicesHelp = R"(usage: loom devices

Lists the Vulkan devices; pick one with --device INDEX|NAME or LOOM_DEVICE.
)";

const char* kRunHelp = R"(usage: loom run [--quiet] SCRIPT.lua [--shard I/N] [ARGS...]

Runs a Lua script with the 'loom' module: renderers, parameters, graph editing, cameras,
images, metrics, CSV/JSON, plots, progress bars and sweeps (see scripts/README.md).
Everything after SCRIPT goes to the script: loom.args holds it, and NAME=VALUE or
--NAME VALUE pairs are read with loom.arg("NAME", default).

  --shard I/N   (anywhere) run only the values I, I+N, I+2N, ... (0 <= I < N) of every
                loom.sweep; loom.write_csv(P) then writes P's part, DIR/STEM.PART-I.csv,
                tagged with the sweep's id; join the parts with 'loom merge'
  --shard slurm (anywhere) the shard of this Slurm array task (SLURM_ARRAY_TASK_ID - _MIN of
                SLURM_ARRAY_TASK_COUNT); the default when SLURM_ARRAY_TASK_ID is set
  --phase merge (anywhere) loom.phase = "merge" and loom.sweep yields nothing: the script's
                plot step on merged CSVs (what a sweep's merge job runs)
  --quiet       (before SCRIPT) print only errors
  --gpu-timeout S  (before SCRIPT) GPU watchdog per submit, as for loom render

A Lua error prints script:line, the message and a traceback, and exits 2.
Example: loom run scripts/equal_time.lua width=64 height=64 budget_ms=400
)";

const char* kMergeHelp = R"(usage: loom merge OUT.csv PART.csv [PART.csv ...]
       loom merge --sweep DIR

Concatenates CSV files that have the same header (the shards of a 'loom run --shard' sweep)
into OUT.csv. Rows are sorted by the 'index' column when there is one, so merged shards
equal the unsharded run. Empty files (shards that owned no values) are skipped. Part files
(STEM.PART-I.csv) carry their sweep's id and shard: parts of different sweeps, a shard given
twice or a missing shard are refused.

--sweep DIR merges a 'loom sweep-submit' directory: if any task failed or never ran it names
them and merges nothing; otherwise it merges every CSV the tasks wrote from its parts.
)";

bool isHelp(const std::string& a) {
    return a == "--help" || a == "-h";
}

json parseValue(const std::string& opt, const std::string& v) {
    try {
        return json::parse(v);
    } catch (const json::out_of_range&) {
        throw UsageError(opt + ": number out of range: '" + v + "'");
    } catch (const json::parse_error&) {
        return json(v);  // bare words are strings: --set tm.operator=reinhard
    }
}

std::pair<std::string, std::string> splitAssign(const std::string& opt, const std::string& s) {
    auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
        throw UsageError(opt + " expects NAME=VALUE, got '" + s + "'");
    return {s.substr(0, eq), s.substr(eq + 1)};
}

int cmdRender(const std::vector<std::string>& args) {
    Renderer::Options o;
    uint32_t frames = 1;
    std::string out;
    std::vector<std::pair<std::string, std::string>> outputs, sets;
    bool checkNan = false, timings = false, quiet = false;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= args.size()) throw UsageError(a + " needs a value");
            return args[++i];
        };
        if (isHelp(a)) {
            std::cout << kRenderHelp;
            return 0;
        } else if (a == "--width")
            o.width = parseUint(a, next());
        else if (a == "--height")
            o.height = parseUint(a, next());
        else if (a == "--frames")
            frames = parseUint(a, next());
        else if (a == "--seed")
            o.seed = parseUint(a, next());
        else if (a == "--device")
            o.device = next();
        else if (a == "--scene")
            o.scene = next();
        else if (a == "--define") {
            auto [k, v] = splitAssign(a, next());
            o.sceneDefines[k] = v;
        } else if (a == "--out")
            out = next();
        else if (a == "--output")
            outputs.push_back(splitAssign(a, next()));
        else if (a == "--set")
            sets.push_back(splitAssign(a, next()));
        else if (a == "--check-nan")
            checkNan = true;
        else if (a == "--timings")
            timings = true;
        else if (a == "--validation")
            o.validation = true;
        else if (a == "--gpu-timeout")
            cli::setGpuTimeout(cli::parseSeconds(a, next()));
        else if (a == "--quiet") {
            quiet = true;
            setLogLevel(LogLevel::Error);
        } else if (a.rfind("--", 0) == 0)
            throw UsageError("render: unknown option '" + a + "' (see loom render --help)");
        else if (o.graph.empty())
            o.graph = a;
        else
            throw UsageError("render: unexpected argument '" + a + "'");
    }
    if (o.graph.empty()) throw UsageError("render: missing GRAPH (see loom render --help)");
    if (o.width == 0 || o.height == 0 || o.width > 16384 || o.height > 16384)
        throw UsageError("render: --width/--height must be in 1..16384");
    if (frames == 0) throw UsageError("render: --frames must be at least 1");

    Renderer r(o);
    for (auto& [k, v] : sets) r.graph().setParam(k, parseValue("--set " + k, v));
    logInfo("device: {}", r.gpu().deviceInfo().name);
    std::map<std::string, double> passMs, statSums;
    // Timings skip the first frame when there are more: drivers such as lavapipe compile
    // pipelines at their first dispatch, inside the GPU timestamps.
    // Every output is resolved and its path checked before the first frame, so that a bad path
    // fails now and not after a long render.
    if (outputs.empty()) {
        if (out.empty()) out = "out/" + r.graph().name() + ".png";
        outputs.push_back({portForOut(r.graph(), out), out});
    } else if (!out.empty()) {
        outputs.insert(outputs.begin(), {portForOut(r.graph(), out), out});
    }
    for (auto& [port, file] : outputs) {
        const auto& marked = r.graph().outputs();
        if (std::find(marked.begin(), marked.end(), port) == marked.end()) {
            std::string list;
            for (auto& m : marked) list += (list.empty() ? "" : ", ") + m;
            throw UsageError("--output " + port + "=" + file + ": '" + port +
                             "' is not a marked output of graph '" + r.graph().name() +
                             "' (marked: " + list + ")");
        }
        checkImagePath(file);
    }
    uint32_t timed = frames > 1 ? frames - 1 : 1;
    auto start = std::chrono::steady_clock::now();
    for (uint32_t f = 0; f < frames; ++f) {
        if (f == frames - timed) {
            passMs.clear();
            statSums.clear();
            start = std::chrono::steady_clock::now();
        }
        r.frame();
        for (auto& t : r.graph().timings()) passMs[t.pass] += t.gpuMs;
        for (auto& p : r.graph().passes())
            for (auto& [k, v] : p->stats()) statSums[p->name() + "." + k] += v;
    }
    double wallMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (checkNan) r.checkNaN();

    for (auto& [port, file] : outputs) {
        writeImage(file, r.readOutput(port));
        if (!quiet)
            std::printf("wrote %s (%s, %ux%u, %u frame%s)\n", file.c_str(), port.c_str(), o.width,
                        o.height, frames, frames == 1 ? "" : "s");
    }
    if (timings) {
        std::printf("%-24s %10s\n", "pass", "GPU ms");
        double total = 0;
        for (auto& t : r.graph().timings()) {
            std::printf("%-24s %10.3f\n", t.pass.c_str(), passMs[t.pass] / timed);
            total += passMs[t.pass] / timed;
        }
        std::printf("%-24s %10.3f\n%-24s %10.3f\n", "total (GPU)", total, "frame (wall)",
                    wallMs / timed);
        // Throughput of passes that count their rays.
        for (auto& p : r.graph().passes()) {
            auto it = statSums.find(p->name() + ".rays");
            if (it == statSums.end() || passMs[p->name()] <= 0) continue;
            std::printf("%-24s %10.2f Mrays/s (%.0f rays/frame)\n", (p->name() + " rays").c_str(),
                        it->second / (passMs[p->name()] * 1e3), it->second / timed);
        }
        // Memory per graph resource, from the same report the inspector shows.
        std::printf("\n%s", formatMemoryReport(r.graph().memoryReport()).c_str());
    }
    for (auto& p : r.graph().passes())
        for (auto& [k, v] : p->stats()) logInfo("{}.{} = {}", p->name(), k, v);
    return 0;
}

int cmdRun(const std::vector<std::string>& args) {
    script::LuaRuntime::Options o;
    std::string file;
    bool sharded = false;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--shard" || a.rfind("--shard=", 0) == 0) {
            std::string v = a == "--shard" ? "" : a.substr(8);
            if (v.empty()) {
                if (i + 1 >= args.size()) throw UsageError("--shard needs a value I/N");
                v = args[++i];
            }
            if (v == "slurm") {
                if (!sweep::slurmShard(o.shardIndex, o.shardCount))
                    throw UsageError(
                        "--shard slurm: SLURM_ARRAY_TASK_ID is not set (not a Slurm "
                        "array task)");
            } else {
                script::parseShard(v, o.shardIndex, o.shardCount);
            }
            sharded = true;
        } else if (a == "--phase") {
            if (i + 1 >= args.size()) throw UsageError("--phase needs a value (run or merge)");
            o.phase = args[++i];
        } else if (!file.empty()) {
            o.args.push_back(a);
        } else if (isHelp(a)) {
            std::cout << kRunHelp;
            return 0;
        } else if (a == "--quiet") {
            setLogLevel(LogLevel::Error);
        } else if (a == "--gpu-timeout") {
            if (i + 1 >= args.size()) throw UsageError("--gpu-timeout needs a value");
            cli::setGpuTimeout(cli::parseSeconds(a, args[++i]));
        } else if (a.rfind("--", 0) == 0) {
            throw UsageError("run: unknown option '" + a + "' (see loom run --help)");
        } else {
            file = a;
        }
    }
    if (file.empty()) throw UsageError("run: missing SCRIPT (see loom run --help)");
    if (!std::filesystem::exists(file)) throw UsageError("run: script not found: '" + file + "'");
    if (!sharded) sweep::slurmShard(o.shardIndex, o.shardCount);
    if (o.shardCount > 1) {
        o.sweepId = sweep::sweepId(file, o.args);
        if (const char* d = std::getenv("LOOM_SWEEP_DIR"); d && *d) o.sweepDir = d;
        logInfo("shard {}/{} of sweep {}", o.shardIndex, o.shardCount, o.sweepId);
    }
    script::LuaRuntime lua(o);
    return lua.runFile(file);
}

int cmdMerge(const std::vector<std::string>& args) {
    std::vector<std::string> files;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (isHelp(a)) {
            std::cout << kMergeHelp;
            return 0;
        }
        if (a == "--sweep") {
            if (i + 2 != args.size()) throw UsageError("merge --sweep takes one DIR");
            return sweep::mergeDirectory(args[i + 1]);
        }
        if (a.rfind("--", 0) == 0) throw UsageError("merge: unknown option '" + a + "'");
        files.push_back(a);
    }
    if (files.size() < 2)
        throw UsageError("merge: expected OUT.csv PART.csv... (see loom merge --help)");
    std::vector<std::string> parts(files.begin() + 1, files.end());
    for (auto& p : parts)
        if (std::filesystem::absolute(p) == std::filesystem::absolute(files[0]))
            throw UsageError("merge: the output '" + files[0] + "' is also an input");
    script::CsvTable merged = script::mergeCsv(parts);
    script::writeCsv(files[0], merged);
    std::printf("wrote %s (%zu rows from %zu files)\n", files[0].c_str(), merged.rows.size(),
                parts.size());
    return 0;
}

int cmdValidate(const std::vector<std::string>& args) {
    std::vector<std::string> files;
    for (auto& a : args) {
        if (isHelp(a)) {
            std::cout << kValidateHelp;
            return 0;
        }
        if (a.rfind("--", 0) == 0) throw UsageError("validate: unknown option '" + a + "'");
        files.push_back(a);
    }
    if (files.empty()) throw UsageError("validate: missing GRAPH (see loom validate --help)");
    int failures = 0;
    // Shaders compile on the default device (lavapipe runs on the CPU), started on first need.
    std::shared_ptr<gpu::Context> gpuContext;
    std::unique_ptr<ShaderCompiler> compiler;
    for (auto& f : files) {
        try {
            auto g = RenderGraph::load(f);
            auto cg = g->compile(256, 256);
            if (!gpuContext) gpuContext = gpu::Context::create(gpu::Context::Options{});
            compiler =
                std::make_unique<ShaderCompiler>(defaultShaderPaths(), gpuContext->cacheDir());
            compiler->addSearchPath(g->sourceDir());
            ShaderLibrary shaders(*gpuContext, *compiler);
            g->compilePasses(shaders, cg.order);
            std::printf("OK %s (%zu passes, %zu culled)\n", f.c_str(), cg.order.size(),
                        cg.culled.size());
        } catch (const UserError& e) {
            // Pass and shader errors name the pass; the file says which graph it is in.
            std::string msg = e.what();
            if (msg.find(f) == std::string::npos) msg = f + ": " + msg;
            std::fprintf(stderr, "error: %s\n", msg.c_str());
            ++failures;
        }
    }
    return failures ? 2 : 0;
}

json bufferSize(const SizeRule& size) {
    if (size.mode == SizeRule::Mode::Fixed) return {{"bytes", size.bytes}};
    return {{"bytesPerPixel", size.bytesPerPixel}, {"extraBytes", size.extraBytes}};
}

json passesJson() {
    json all = json::array();
    for (auto& type : PassRegistry::instance().types()) {
        auto pass = PassRegistry::instance().create(type, "p");
        PassReflection r = pass->reflection();
        json j{{"type", type}, {"doc", PassRegistry::instance().find(type)->doc}};
        j["inputs"] = json::array();
        j["outputs"] = json::array();
        for (auto& p : r.ports()) {
            json pj{{"name", p.name},
                    {"kind", p.kind == ResourceKind::Texture ? "texture" : "buffer"},
                    {"optional", p.optional},
                    {"doc", p.doc}};
            if (p.kind == ResourceKind::Texture)
                pj["format"] = p.format ? gpu::formatName(*p.format) : "any";
            if (p.previousFrame) pj["previousFrame"] = true;
            if (p.kind == ResourceKind::Buffer && !p.isInput) pj["size"] = bufferSize(p.size);
            if (!p.inPlaceOf.empty()) pj["inPlaceOf"] = p.inPlaceOf;
            j[p.isInput ? "inputs" : "outputs"].push_back(pj);
        }
        // Scratch lives only during the pass; listed so that docs and tools see its memory.
        j["scratch"] = json::array();
        for (auto& p : r.scratch()) {
            json pj{{"name", p.name},
                    {"kind", p.kind == ResourceKind::Texture ? "texture" : "buffer"},
                    {"doc", p.doc}};
            if (p.kind == ResourceKind::Texture)
                pj["format"] = gpu::formatName(p.format.value_or(gpu::Format::RGBA32F));
            else
                pj["size"] = bufferSize(p.size);
            j["scratch"].push_back(pj);
        }
        j["params"] = json::array();
        for (auto& p : r.params()) {
            json pj{{"name", p.name},
                    {"type", paramTypeName(p.type)},
                    {"default", p.defaultValue},
                    {"doc", p.doc}};
            if (p.min) pj["min"] = *p.min;
            if (p.max) pj["max"] = *p.max;
            if (!p.choices.empty()) pj["choices"] = p.choices;
            j["params"].push_back(pj);
        }
        j["persistent"] = json::array();
        for (auto& p : r.persistent())
            j["persistent"].push_back({{"name", p.name}, {"doc", p.doc}});
        all.push_back(j);
    }
    return all;
}

int cmdPasses(const std::vector<std::string>& args) {
    bool asJson = false;
    for (auto& a : args) {
        if (isHelp(a)) {
            std::cout << kPassesHelp;
            return 0;
        }
    }
    json all = passesJson();
    if (!args.empty() && (args[0] == "--update-docs" || args[0] == "--check-docs")) {
        std::vector<std::string> files(args.begin() + 1, args.end());
        if (files.empty()) throw UsageError("passes: " + args[0] + " needs README files");
        bool check = args[0] == "--check-docs";
        int n = updatePassDocs(all, files, check);
        if (!check) std::printf("%d table block(s) updated\n", n);
        return check && n ? 2 : 0;
    }
    if (!args.empty() && args[0] == "--markdown") {
        if (args.size() != 2) throw UsageError("passes: --markdown needs one pass TYPE");
        for (auto& p : all)
            if (p["type"] == args[1]) {
                std::cout << passTablesMarkdown(p);
                return 0;
            }
        throw UserError("passes: unknown pass type '" + args[1] + "'");
    }
    for (auto& a : args) {
        if (a == "--json")
            asJson = true;
        else
            throw UsageError("passes: unknown option '" + a + "'");
    }
    if (asJson) {
        std::cout << all.dump(2) << "\n";
        return 0;
    }
    for (auto& p : all) {
        std::cout << p["type"].get<std::string>() << " - " << p["doc"].get<std::string>() << "\n";
        for (const char* dir : {"inputs", "outputs"})
            for (auto& port : p[dir])
                std::cout << "  " << (dir[0] == 'i' ? "in  " : "out ")
                          << port["name"].get<std::string>() << " : "
                          << port["kind"].get<std::string>() << (port.contains("format") ? " " : "")
                          << (port.contains("format") ? port["format"].get<std::string>() : "")
                          << (port["optional"].get<bool>() ? " (optional)" : "")
                          << (port.contains("inPlaceOf")
                                  ? " (in place of " + port["inPlaceOf"].get<std::string>() + ")"
                                  : "")
                          << "  " << port["doc"].get<std::string>() << "\n";
        for (auto& s : p["scratch"])
            std::cout << "  scratch " << s["name"].get<std::string>() << " : "
                      << s["kind"].get<std::string>() << "  " << s["doc"].get<std::string>()
                      << "\n";
        for (auto& param : p["params"]) {
            std::cout << "  param " << param["name"].get<std::string>() << " : "
                      << param["type"].get<std::string>() << " = " << param["default"].dump();
            if (param.contains("min") || param.contains("max"))
                std::cout << " in [" << (param.contains("min") ? param["min"].dump() : "-inf")
                          << ", " << (param.contains("max") ? param["max"].dump() : "inf") << "]";
            if (param.contains("choices")) std::cout << " of " << param["choices"].dump();
            std::cout << "  " << param["doc"].get<std::string>() << "\n";
        }
    }
    return 0;
}

int cmdDevices(const std::vector<std::string>& args) {
    for (auto& a : args) {
        if (isHelp(a)) {
            std::cout << kDevicesHelp;
            return 0;
        }
        throw UsageError("devices: unknown option '" + a + "'");
    }
    for (auto& d : gpu::Context::listDevices())
        std::printf("%u: %s (%s, Vulkan %u.%u, %s)\n", d.index, d.name.c_str(), d.type.c_str(),
                    VK_API_VERSION_MAJOR(d.apiVersion), VK_API_VERSION_MINOR(d.apiVersion),
                    d.driver.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    // Past a file-size limit (ulimit -f) a write then fails with EFBIG and is reported,
    // instead of the process being killed half-way through a file.
    std::signal(SIGXFSZ, SIG_IGN);
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || isHelp(args[0])) {
        std::cout << kMainHelp;
        return args.empty() ? 2 : 0;
    }
    std::string cmd = args[0];
    args.erase(args.begin());
    try {
        cli::setGpuTimeout(cli::defaultGpuTimeout());
        if (cmd == "render") return cmdRender(args);
        if (cmd == "validate") return cmdValidate(args);
        if (cmd == "passes") return cmdPasses(args);
        if (cmd == "devices") return cmdDevices(args);
        if (cmd == "run") return cmdRun(args);
        if (cmd == "merge") return cmdMerge(args);
        if (cmd == "sweep-submit") return sweep::submit(args);
        throw UsageError("unknown command '" + cmd +
                         "' (commands: render, validate, passes, devices, run, merge, "
                         "sweep-submit)");
    } catch (const UserError& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "internal error: %s\n", e.what());
        return 1;
    }
}
