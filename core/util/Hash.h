#pragma once
#include <cstdint>
#include <string>
#include <string_view>

namespace loom {

// 64-bit FNV-1a; used for cache keys (collisions only cost a recompile check, see ShaderCache).
struct Hasher {
    uint64_t h = 1469598103934665603ull;
    Hasher& add(std::string_view s) {
        for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
        // Separator so ("ab","c") and ("a","bc") differ.
        h = (h ^ 0xff) * 1099511628211ull;
        return *this;
    }
    Hasher& add(uint64_t v) { return add(std::string_view(reinterpret_cast<const char*>(&v), 8)); }
    std::string hex() const;
};

}  // namespace loom
