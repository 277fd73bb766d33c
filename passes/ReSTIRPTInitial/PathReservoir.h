#pragma once
// Host-side facts about the ReSTIR PT buffers shared by the ReSTIRPT* passes; the layouts are
// defined in shaders/lib/restir/path_reservoir.glsl.
#include <map>
#include <memory>
#include <string>

#include "core/gpu/Context.h"

namespace loom::restir {

constexpr uint64_t kSettingsBytes = 32;    // RestirSettings header of a reservoir buffer
constexpr uint64_t kReservoirBytes = 112;  // PathReservoir
constexpr uint64_t kPrimaryHitBytes = 32;  // PrimaryHit

// Shift attempt/success counters (RestirCounters in path_shift.glsl), exposed as pass stats.
class ShiftCounters {
public:
    std::shared_ptr<gpu::Buffer> reset(gpu::Context& gpu, gpu::CommandList& cmd) {
        if (!mBuffer) mBuffer = gpu.createBuffer(16, "RestirCounters");
        cmd.fillBuffer(*mBuffer, 0);
        cmd.barrier();
        return mBuffer;
    }
    void read(gpu::Context& gpu) {
        if (mBuffer) gpu.downloadBuffer(*mBuffer, mValues, sizeof(mValues));
    }
    void addStats(std::map<std::string, double>& s) const {
        s["shiftAttemptsReconnect"] = mValues[0];
        s["shiftSuccessReconnect"] = mValues[1];
        s["shiftAttemptsReplay"] = mValues[2];
        s["shiftSuccessReplay"] = mValues[3];
        double attempts = double(mValues[0]) + mValues[2];
        s["reconnectShare"] = attempts > 0 ? mValues[0] / attempts : 0.0;
    }

private:
    std::shared_ptr<gpu::Buffer> mBuffer;
    uint32_t mValues[4] = {0, 0, 0, 0};
};

}  // namespace loom::restir
