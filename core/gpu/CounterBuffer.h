#pragma once
// A few uint32 counters a kernel increments atomically (rays traced, shift attempts), zeroed
// at the start of a pass and read back after the frame for the pass's stats().
#include <array>
#include <memory>
#include <string>

#include "core/gpu/Context.h"

namespace loom::gpu {

template <size_t N>
class CounterBuffer {
public:
    explicit CounterBuffer(std::string name) : mName(std::move(name)) {}
    // Zeroes the counters inside the pass's command list; returns the buffer to bind.
    std::shared_ptr<Buffer> reset(Context& gpu, CommandList& cmd) {
        if (!mBuffer) mBuffer = gpu.createBuffer(std::max<size_t>(16, N * 4), mName);
        cmd.fillBuffer(*mBuffer, 0);
        cmd.barrier();
        return mBuffer;
    }
    // After the frame's GPU work finished (Pass::frameCompleted).
    void read(Context& gpu) {
        if (mBuffer) gpu.downloadBuffer(*mBuffer, mValues.data(), N * 4);
    }
    uint32_t operator[](size_t i) const { return mValues[i]; }

private:
    std::string mName;
    std::shared_ptr<Buffer> mBuffer;
    std::array<uint32_t, N> mValues{};
};

}  // namespace loom::gpu
