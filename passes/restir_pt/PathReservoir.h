#pragma once
// Host-side facts about the ReSTIR PT buffers shared by the ReSTIRPT* passes; the layouts are
// defined in shaders/lib/restir/reservoir.glsl.
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/gpu/Context.h"
#include "core/gpu/CounterBuffer.h"
#include "core/graph/KernelParams.h"
#include "core/graph/Pass.h"

namespace loom::restir {

constexpr uint64_t kSettingsBytes = 48;    // RestirSettings header of a reservoir buffer
constexpr uint64_t kReservoirBytes = 112;  // PathReservoir
constexpr uint64_t kPrimaryHitBytes = 32;  // PrimaryHit

// The element sizes above are checked against the kernels' SPIR-V strides when they bind the
// buffers (KernelParams). Shared enums (SHIFT, DOF_SHIFT) are registered in PathReservoir.cpp.

// The ports and parameters of temporal reuse by gathering (ReSTIRPTTemporal, and
// ReservoirSplatTemporal's gather mode, which runs the same kernel): declared once here.
void reflectTemporalReuse(PassReflection& r);

// Shift attempt/success and ray counters (RestirCounters in counters.glsl), exposed as pass
// stats.
class ShiftCounters {
public:
    std::shared_ptr<gpu::Buffer> reset(gpu::Context& gpu, gpu::CommandList& cmd) {
        return mCounters.reset(gpu, cmd);
    }
    void read(gpu::Context& gpu) { mCounters.read(gpu); }
    std::map<std::string, double> stats() const {
        double attempts = double(mCounters[0]) + mCounters[2];
        return {{"shiftAttemptsReconnect", mCounters[0]},
                {"shiftSuccessReconnect", mCounters[1]},
                {"shiftAttemptsReplay", mCounters[2]},
                {"shiftSuccessReplay", mCounters[3]},
                {"reconnectShare", attempts > 0 ? mCounters[0] / attempts : 0.0},
                {"rays", mCounters[4]},
                {"maxTraversalSteps", mCounters[5]}};
    }

private:
    gpu::CounterBuffer<6> mCounters{"RestirCounters"};
};

// A pass whose kernels shift paths, with the shift counters as its stats.
class ShiftCountingPass : public Pass {
public:
    void frameCompleted(gpu::Context& gpu) override { mCounters.read(gpu); }
    std::map<std::string, double> stats() const override { return mCounters.stats(); }

protected:
    ShiftCounters mCounters;
};

// Binds the scene and reflectTemporalReuse's ports under the temporal kernels' block names, and
// the shift counters (zeroed).
gpu::Bindings temporalReuseBindings(ExecuteContext& ctx, ShiftCounters& counters);

// Spatial reuse in `rounds` rounds, each reading the previous one's reservoirs: round r reads
// `in` (r = 0) or round r - 1's output, and writes `out` or `pingPong` alternately so that the
// last round writes `out`. bind(b, src, dst) adds the round's bindings to the scene's; each
// round is one width x height dispatch of `pipeline` with its `round` member set.
void dispatchSpatialRounds(
    const Pass& pass, const gpu::ComputePipeline& pipeline, ExecuteContext& ctx, int rounds,
    std::shared_ptr<gpu::Buffer> in, const std::shared_ptr<gpu::Buffer>& out,
    const std::shared_ptr<gpu::Buffer>& pingPong,
    const std::function<void(gpu::Bindings&, const std::shared_ptr<gpu::Buffer>& src,
                             const std::shared_ptr<gpu::Buffer>& dst)>& bind);

}  // namespace loom::restir
