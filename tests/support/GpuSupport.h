#pragma once
// One gpu::Context per test executable (lavapipe unless LOOM_DEVICE says otherwise), with its
// shader and pipeline caches in a temporary directory removed at exit.
#include <memory>
#include <string>

#include "core/gpu/Context.h"
#include "tests/support/TestSupport.h"

namespace loom::test {

struct SharedGpu {
    TempDir cache{"loom-gpu-cache"};  // declared first: destroyed after the context
    std::shared_ptr<gpu::Context> context;
    SharedGpu() {
        gpu::Context::Options o;
        o.cacheDir = cache.str();
        context = gpu::Context::create(o);
    }
};

inline SharedGpu& sharedGpu() {
    static SharedGpu gpu;
    return gpu;
}

inline std::shared_ptr<gpu::Context> gpuContext() {
    return sharedGpu().context;
}
inline std::string gpuCacheDir() {
    return sharedGpu().cache.str();
}

}  // namespace loom::test
