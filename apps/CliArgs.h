#pragma once
// Command-line helpers shared by the loom and loom-inspector executables: usage errors (exit
// code 2, like every other bad input) and strict integer parsing.
#include <stdexcept>
#include <string>

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

}  // namespace loom::cli
