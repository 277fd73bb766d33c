#include "apps/loom/Sweep.h"

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "apps/CliArgs.h"
#include "core/graph/Renderer.h"
#include "core/script/Csv.h"
#include "core/util/AtomicFile.h"
#include "core/util/Hash.h"
#include "core/util/JsonSource.h"

namespace loom::sweep {

namespace fs = std::filesystem;
using cli::UsageError;
using json = nlohmann::json;

const char* kSubmitHelp =
    R"(usage: loom sweep-submit SCRIPT.lua [ARGS...] --tasks N [--dir DIR] [--sbatch OPT]...
       loom sweep-submit --retry DIR [--sbatch OPT]...

Submits a Lua sweep (loom.sweep) to Slurm as a job array of N tasks, task I running shard I/N
(loom run --shard slurm), and a merge job that runs when every task has ended: it checks each
task's exit status (naming any that failed, and merging nothing), merges every CSV the tasks
wrote (loom merge --sweep DIR), then runs the script once more with --phase merge for its
plot step. Prints the job ids and where the results appear.

  --tasks N      array tasks (shards)
  --dir DIR      sweep directory: job scripts, logs/, status/, parts/ (default
                 out/sweeps/SCRIPT-ID)
  --sbatch OPT   extra sbatch option for both jobs, e.g. --sbatch --partition=gpu (repeatable)
  --retry DIR    resubmit only the tasks of DIR that failed or never ran (--array=3,5), and a
                 new merge job

The job scripts come from scripts/slurm/sweep.sbatch and merge.sbatch. SLURM_CONF and the
usual Slurm environment apply; tools/slurm-local.sh starts a one-node cluster to try it.
)";

namespace {

std::string readText(const std::string& path, const std::string& what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError("cannot read " + what + " '" + path + "'");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string shellQuote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

uint32_t envUint(const char* name, bool required) {
    const char* v = std::getenv(name);
    if (!v || !*v) {
        if (required) throw UserError(std::string("--shard slurm: ") + name + " is not set");
        return 0;
    }
    return cli::parseUint(name, v);
}

// Runs a command, returns its stdout; a failure names the command and its output.
std::string runCommand(const std::string& cmd, const std::string& what) {
    FILE* p = popen((cmd + " 2>&1").c_str(), "r");
    if (!p) throw UserError("cannot run " + what);
    std::string out;
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof(buf), p)) > 0) out.append(buf, n);
    int status = pclose(p);
    if (status != 0) {
        while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
        throw UserError(fmt::format("{} failed: {}\n  command: {}", what, out, cmd));
    }
    return out;
}

std::string templateText(const std::string& name) {
    std::string root = dataRoot();
    if (root.empty()) throw UserError("cannot find Loom's scripts/slurm templates");
    return readText(root + "/scripts/slurm/" + name, "job template");
}

std::string fill(std::string text, const std::map<std::string, std::string>& fields) {
    for (const auto& [key, value] : fields) {
        std::string tag = "@" + key + "@";
        for (size_t at = text.find(tag); at != std::string::npos;
             at = text.find(tag, at + value.size()))
            text.replace(at, tag.size(), value);
    }
    return text;
}

// What a sweep directory holds about its sweep (sweep.json, written at submission).
struct Sweep {
    std::string script, workdir, id, dir;
    std::vector<std::string> args, sbatch;
    uint32_t tasks = 0;
};

Sweep loadSweep(const std::string& dir) {
    std::string file = dir + "/sweep.json";
    if (!fs::exists(file))
        throw UserError(dir + ": not a sweep directory (no sweep.json; see loom sweep-submit)");
    json j = JsonSource::load(file).root();
    Sweep s;
    try {
        s.script = j.at("script").get<std::string>();
        s.workdir = j.at("workdir").get<std::string>();
        s.id = j.at("id").get<std::string>();
        s.args = j.at("args").get<std::vector<std::string>>();
        s.sbatch = j.at("sbatch").get<std::vector<std::string>>();
        s.tasks = j.at("tasks").get<uint32_t>();
    } catch (const json::exception& e) {
        throw UserError(file + ": " + e.what());
    }
    if (s.tasks == 0) throw UserError(file + ": 'tasks' must be at least 1");
    s.dir = fs::absolute(dir).lexically_normal().string();
    return s;
}

// Writes the job scripts and submits the array (`array`: "0-3" or "3,5") and its merge job.
void submitJobs(const Sweep& s, const std::string& array) {
    std::string exe = fs::read_symlink("/proc/self/exe").string();
    std::string args;
    for (const auto& a : s.args) args += " " + shellQuote(a);
    std::map<std::string, std::string> fields = {
        {"NAME", fs::path(s.script).stem().string()},
        {"DIR", shellQuote(s.dir)},
        {"WORKDIR", shellQuote(s.workdir)},
        {"SWEEP_ID", shellQuote(s.id)},
        {"TASKS", std::to_string(s.tasks)},
        {"LOOM", shellQuote(exe)},
        {"SCRIPT", shellQuote(s.script)},
        {"ARGS", args.empty() ? "" : args.substr(1)},
    };
    // Inside #SBATCH lines paths are not shell-parsed: no quotes there.
    auto fillJob = [&](const std::string& name) {
        std::string text = fill(templateText(name), {{"NAME", fields["NAME"]}});
        std::string out;
        std::stringstream lines(text);
        for (std::string line; std::getline(lines, line);) {
            auto f = fields;
            if (line.rfind("#SBATCH", 0) == 0) f["DIR"] = s.dir;
            out += fill(line, f) + "\n";
        }
        writeTextFileAtomic(s.dir + "/" + name, "job script", out);
        fs::permissions(s.dir + "/" + name, fs::perms::owner_exec, fs::perm_options::add);
    };
    fillJob("sweep.sbatch");
    fillJob("merge.sbatch");
    std::string extra;
    for (const auto& o : s.sbatch) extra += " " + shellQuote(o);
    std::string arrayId = runCommand("timeout 120 sbatch --parsable --array=" + array + extra +
                                         " " + shellQuote(s.dir + "/sweep.sbatch"),
                                     "sbatch (array job)");
    arrayId = arrayId.substr(0, arrayId.find_first_of(";\n"));
    std::string mergeId =
        runCommand("timeout 120 sbatch --parsable --dependency=afterany:" + arrayId + extra + " " +
                       shellQuote(s.dir + "/merge.sbatch"),
                   "sbatch (merge job)");
    mergeId = mergeId.substr(0, mergeId.find_first_of(";\n"));
    {
        std::ofstream jobs(s.dir + "/jobs.txt", std::ios::app);
        jobs << "array " << arrayId << " tasks " << array << "\nmerge " << mergeId << "\n";
    }
    std::printf("sweep %s: array job %s (tasks %s of %u), merge job %s (after %s)\n", s.id.c_str(),
                arrayId.c_str(), array.c_str(), s.tasks, mergeId.c_str(), arrayId.c_str());
    std::printf("  directory:   %s (logs/, status/, parts/)\n", s.dir.c_str());
    std::string out;
    for (const auto& a : s.args)
        if (a.rfind("out=", 0) == 0) out = a.substr(4);
    std::printf("  results:     %s/merged.txt lists the merged CSVs%s when job %s ends\n",
                s.dir.c_str(), out.empty() ? "" : (", in " + out + "/ with the plot").c_str(),
                mergeId.c_str());
    std::printf("  done when:   %s/DONE exists; a failed task is named in logs/merge.out\n",
                s.dir.c_str());
}

// Tasks whose status file is missing or holds a non-zero exit code.
std::map<uint32_t, std::string> failedTasks(const Sweep& s) {
    std::map<uint32_t, std::string> failed;
    for (uint32_t i = 0; i < s.tasks; ++i) {
        std::string file = fmt::format("{}/status/task-{}.rc", s.dir, i);
        if (!fs::exists(file)) {
            failed[i] = "no exit status: it did not run, or was killed";
            continue;
        }
        std::string rc = readText(file, "task status");
        while (!rc.empty() && (rc.back() == '\n' || rc.back() == ' ')) rc.pop_back();
        if (rc != "0") failed[i] = "exit code " + rc;
    }
    return failed;
}

}  // namespace

bool slurmShard(uint32_t& index, uint32_t& count) {
    if (!std::getenv("SLURM_ARRAY_TASK_ID")) return false;
    uint32_t id = envUint("SLURM_ARRAY_TASK_ID", true);
    uint32_t base = 0;
    if (uint32_t tasks = envUint("LOOM_SWEEP_TASKS", false); tasks > 0) {
        count = tasks;
    } else {
        base = envUint("SLURM_ARRAY_TASK_MIN", true);
        count = envUint("SLURM_ARRAY_TASK_COUNT", true);
    }
    if (id < base || id - base >= count || count == 0)
        throw UserError(
            fmt::format("--shard slurm: task {} is not in [{}, {}) (SLURM_ARRAY_TASK_*"
                        " / LOOM_SWEEP_TASKS)",
                        id, base, base + count));
    index = id - base;
    return true;
}

std::string sweepId(const std::string& script, const std::vector<std::string>& args) {
    if (const char* env = std::getenv("LOOM_SWEEP_ID"); env && *env) return env;
    Hasher h;
    h.add(fs::path(script).filename().string());
    std::ifstream in(script, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    h.add(ss.str());
    for (const auto& a : args) h.add(a);
    return h.hex().substr(0, 12);
}

int mergeDirectory(const std::string& dir) {
    Sweep s = loadSweep(dir);
    auto failed = failedTasks(s);
    if (!failed.empty()) {
        std::string list, ids;
        for (const auto& [i, why] : failed) {
            list += fmt::format("\n  task {}: {} (log: {}/logs/task-{}.out)", i, why, s.dir, i);
            if (!ids.empty()) ids += ',';
            ids += std::to_string(i);
        }
        throw UserError(fmt::format(
            "sweep {}: {} of {} tasks failed, nothing merged:{}\n  resubmit them (--array={}): "
            "loom sweep-submit --retry {}",
            s.id, failed.size(), s.tasks, list, ids, s.dir));
    }
    // Every CSV any task wrote; a task whose shard owned no values may have written none.
    std::set<std::string> csvs;
    for (uint32_t i = 0; i < s.tasks; ++i) {
        std::string manifest = fmt::format("{}/parts/task-{}.txt", s.dir, i);
        if (!fs::exists(manifest)) continue;
        std::stringstream lines(readText(manifest, "sweep manifest"));
        for (std::string line; std::getline(lines, line);)
            if (!line.empty()) csvs.insert(line);
    }
    if (csvs.empty()) throw UserError("sweep " + s.id + ": no task wrote a CSV (loom.write_csv)");
    // Merge everything in memory first: a bad part leaves no merged file behind.
    std::vector<std::pair<std::string, script::CsvTable>> merged;
    for (const auto& csv : csvs) {
        std::vector<std::string> parts;
        for (uint32_t i = 0; i < s.tasks; ++i) parts.push_back(script::csvPartPath(csv, i));
        for (const auto& p : parts)
            if (!fs::exists(p))
                throw UserError(
                    fmt::format("sweep {}: {} is missing (its task succeeded but did "
                                "not write it), nothing merged",
                                s.id, p));
        script::CsvTable table = script::mergeCsv(parts);
        if (!table.rows.empty() || !table.header.empty())
            merged.emplace_back(csv, std::move(table));
    }
    std::string list;
    for (const auto& [csv, table] : merged) {
        script::writeCsv(csv, table);
        std::printf("merged %u parts into %s (%zu rows)\n", s.tasks, csv.c_str(),
                    table.rows.size());
        list += csv + "\n";
    }
    writeTextFileAtomic(s.dir + "/merged.txt", "merged list", list);
    return 0;
}

int submit(const std::vector<std::string>& args) {
    Sweep s;
    std::string retry, dir;
    bool haveTasks = false;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= args.size()) throw UsageError(a + " needs a value");
            return args[++i];
        };
        if (!s.script.empty() && a != "--tasks" && a != "--dir" && a != "--sbatch") {
            s.args.push_back(a);
        } else if (a == "--help" || a == "-h") {
            std::fputs(kSubmitHelp, stdout);
            return 0;
        } else if (a == "--tasks") {
            s.tasks = cli::parseUint(a, next());
            haveTasks = true;
        } else if (a == "--dir") {
            dir = next();
        } else if (a == "--sbatch") {
            s.sbatch.push_back(next());
        } else if (a == "--retry") {
            retry = next();
        } else if (a.rfind("--", 0) == 0) {
            throw UsageError("sweep-submit: unknown option '" + a +
                             "' (see loom sweep-submit --help)");
        } else {
            s.script = a;
        }
    }
    runCommand("command -v sbatch",
               "finding sbatch (is Slurm installed? apt-get install slurm-client)");
    if (!retry.empty()) {
        if (!s.script.empty() || haveTasks)
            throw UsageError("sweep-submit --retry DIR takes no SCRIPT or --tasks");
        auto extra = s.sbatch;
        s = loadSweep(retry);
        if (!extra.empty()) s.sbatch = extra;
        auto failed = failedTasks(s);
        if (failed.empty()) {
            std::printf("sweep %s: every task succeeded; nothing to resubmit\n", s.id.c_str());
            return 0;
        }
        std::string ids;
        for (const auto& [i, why] : failed) {
            if (!ids.empty()) ids += ',';
            ids += std::to_string(i);
            fs::remove(fmt::format("{}/status/task-{}.rc", s.dir, i));
        }
        submitJobs(s, ids);
        return 0;
    }
    if (s.script.empty())
        throw UsageError("sweep-submit: missing SCRIPT (see loom sweep-submit --help)");
    if (!haveTasks || s.tasks == 0)
        throw UsageError("sweep-submit: --tasks N (N >= 1) is required");
    if (!fs::exists(s.script))
        throw UsageError("sweep-submit: script not found: '" + s.script + "'");
    s.script = fs::absolute(s.script).lexically_normal().string();
    s.workdir = fs::current_path().string();
    s.id = sweepId(s.script, s.args);
    if (dir.empty()) dir = "out/sweeps/" + fs::path(s.script).stem().string() + "-" + s.id;
    s.dir = fs::absolute(dir).lexically_normal().string();
    for (const char* sub : {"logs", "status", "parts"}) fs::create_directories(s.dir + "/" + sub);
    for (const auto& e : fs::directory_iterator(s.dir + "/status")) fs::remove(e.path());
    for (const auto& e : fs::directory_iterator(s.dir + "/parts")) fs::remove(e.path());
    fs::remove(s.dir + "/DONE");
    json j = {{"script", s.script}, {"workdir", s.workdir}, {"id", s.id},
              {"args", s.args},     {"sbatch", s.sbatch},   {"tasks", s.tasks}};
    writeTextFileAtomic(s.dir + "/sweep.json", "sweep description", j.dump(2) + "\n");
    submitJobs(s, "0-" + std::to_string(s.tasks - 1));
    return 0;
}

}  // namespace loom::sweep
