#pragma once
// Command-line helpers shared by the loom and loom-inspector executables: usage errors (exit
// code 2, like every other bad input) and strict integer parsing.
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "core/gpu/Context.h"
#include "core/util/Error.h"

namespace loom::cli {

struct UsageError : UserError {
    using UserError::UserError;
};

inline uint32_t parseUint(const std::string& opt, const std::string& v) {
    try {
        size_t pos = 0;
        long long x = std::stoll(v, &pos);
        if (pos != v.size() || x < 0 || x > 0xffffffffll) throw std::invalid_argument("");
        return uint32_t(x);
    } catch (const std::exception&) {
        throw UsageError(opt + " expects a non-negative integer, got '" + v + "'");
    }
}

// Seconds, finite and >= 0 (0 = no limit).
inline double parseSeconds(const std::string& opt, const std::string& v) {
    try {
        size_t pos = 0;
        double x = std::stod(v, &pos);
        if (pos != v.size() || !(x >= 0.0) || x > 1e9) throw std::invalid_argument("");
        return x;
    } catch (const std::exception&) {
        throw UsageError(opt + " expects seconds (a number >= 0, 0 = no limit), got '" + v + "'");
    }
}

// The GPU watchdog (gpu::Watchdog) for an executable: a submit still running after `seconds`
// prints `prefix` and the message naming the pass, and ends the process with code 2. It must
// end it: the device may still be running the work, so nothing it uses may be freed and no
// destructor may wait for it.
inline void setGpuTimeout(double seconds, const char* prefix = "error: ") {
    static std::string sPrefix;
    sPrefix = prefix;
    gpu::Context::setWatchdog({seconds, [](const std::string& message) {
                                   std::fprintf(stderr, "%s%s\n", sPrefix.c_str(), message.c_str());
                                   std::fflush(stdout);
                                   std::fflush(stderr);
                                   std::_Exit(2);
                               }});
}

// LOOM_GPU_TIMEOUT, else 600 s: long enough for a 1080p frame on lavapipe, short of forever.
inline double defaultGpuTimeout() {
    const char* env = std::getenv("LOOM_GPU_TIMEOUT");
    return env && *env ? parseSeconds("LOOM_GPU_TIMEOUT", env) : 600.0;
}

}  // namespace loom::cli
