#pragma once
// Host side of spatiotemporal reuse with the manifold shift (Hong et al. 2025 Sec. 5): the
// reservoir layout (shaders/lib/manifold/reservoir.glsl), the shift's parameters declared once
// for ManifoldReSTIRTemporal and ManifoldReSTIRSpatial, their bindings and counters.
#include <map>
#include <memory>
#include <string>

#include "core/gpu/CounterBuffer.h"
#include "core/graph/KernelParams.h"
#include "core/graph/Pass.h"

namespace loom {

constexpr uint64_t kManifoldReservoirBytes = 112;       // ManifoldReservoir
constexpr uint64_t kManifoldReservoirHeaderBytes = 16;  // ManifoldReservoirHeader

// Ports and parameters both reuse passes have: the reservoirs out, the caustic they estimate
// and the full image with the path tracer's part, and the manifold shift's settings.
void reflectManifoldReuse(PassReflection& r);

// A reuse pass: compiles its kernel, binds what reflectManifoldReuse declared, counts shifts.
class ManifoldReusePass : public Pass {
public:
    void frameCompleted(gpu::Context& gpu) override;
    std::map<std::string, double> stats() const override;

protected:
    // The kernel for this execution (recompiled when the connected outputs change).
    gpu::ComputePipeline& kernel(ExecuteContext& ctx, const std::string& file);
    // The scene, ReservoirsIn (from `input`), ReservoirsOut, the images and the counters.
    gpu::Bindings bindings(ExecuteContext& ctx, const std::string& input);
    // The shift's members of the kernel's parameters.
    KernelParams params(ExecuteContext& ctx, gpu::ComputePipeline& kernel) const;

private:
    std::map<std::string, std::shared_ptr<gpu::ComputePipeline>> mKernels;
    gpu::CounterBuffer<5> mCounters{"ManifoldReuseCounters"};
    bool mWarnedLoopLimit = false;
};

}  // namespace loom
