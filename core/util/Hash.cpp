#include "core/util/Hash.h"

#include <cstdio>

namespace loom {
std::string Hasher::hex() const {
    char buf[17];
    std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
    return buf;
}
}  // namespace loom
