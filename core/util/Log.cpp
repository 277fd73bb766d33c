#include "core/util/Log.h"

#include <atomic>
#include <cstdlib>
#include <mutex>

namespace loom {

namespace {
LogLevel initialLevel() {
    const char* env = std::getenv("LOOM_LOG");
    if (!env) return LogLevel::Info;
    std::string s = env;
    if (s == "debug") return LogLevel::Debug;
    if (s == "warning") return LogLevel::Warning;
    if (s == "error") return LogLevel::Error;
    if (s == "silent") return LogLevel::Silent;
    return LogLevel::Info;
}
std::atomic<LogLevel> gLevel{initialLevel()};
std::mutex gMutex;
}  // namespace

void setLogLevel(LogLevel level) { gLevel = level; }
LogLevel logLevel() { return gLevel; }

void logMessage(LogLevel level, const std::string& text) {
    if (level < gLevel.load()) return;
    static const char* kPrefix[] = {"[debug] ", "", "warning: ", "error: ", ""};
    std::lock_guard lock(gMutex);
    // Everything goes to stderr so stdout stays machine-readable (loom passes --json).
    std::fprintf(stderr, "%s%s\n", kPrefix[int(level)], text.c_str());
}

}  // namespace loom
