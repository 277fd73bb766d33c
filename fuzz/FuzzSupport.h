#pragma once
// Shared by the harnesses: an input is bad input or it is fine; anything else is a finding.
// UserError is the documented answer to bad input (exit code 2); any other exception would
// reach the CLI as an internal error (exit 1), so it aborts like a crash and is kept.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>

#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom::fuzz {

template <typename F>
int guard(F&& f) {
    static bool quiet = (setLogLevel(LogLevel::Error), true);
    (void)quiet;
    try {
        f();
    } catch (const UserError&) {
    } catch (const std::exception& e) {
        std::fprintf(stderr, "not a UserError: %s\n", e.what());
        std::abort();
    }
    return 0;
}

// The scene loaders read files: the input goes to one per process, with the extension that
// picks the loader.
inline std::string writeInput(const uint8_t* data, size_t size, const std::string& ext) {
    std::string path = "/tmp/loom-fuzz-" + std::to_string(::getpid()) + ext;
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data),
                                                std::streamsize(size));
    return path;
}

}  // namespace loom::fuzz
