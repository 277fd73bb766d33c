#pragma once
// The host side of shaders/lib/work_list.glsl: per-item work continued over a chain of
// indirect dispatches. reset() before the kernel that fills the first list; dispatch i of the
// chain reads its group count at argsOffset(i) of args(). The items (8 bytes each) are the
// pass's own buffer, bound as WorkListItems.
#include <memory>

#include "core/gpu/Context.h"

namespace loom::gpu {

class WorkList {
public:
    void reset(Context& gpu, CommandList& cmd) {
        if (!mCounts) {
            mCounts = gpu.createBuffer(16, "WorkListCounts");
            mArgs = gpu.createBuffer(3 * 16, "WorkListArgs");
        }
        cmd.fillBuffer(*mCounts, 0);
        cmd.fillBuffer(*mArgs, 1u);  // (1, 1, 1) groups each
        cmd.barrier();
    }
    void bind(Bindings& b, const std::shared_ptr<Buffer>& items) const {
        b.set("WorkListCounts", mCounts).set("WorkListArgs", mArgs).set("WorkListItems", items);
    }
    const Buffer& args() const { return *mArgs; }
    static uint64_t argsOffset(int dispatch) { return 16 * uint64_t(dispatch % 3); }

private:
    std::shared_ptr<Buffer> mCounts, mArgs;
};

}  // namespace loom::gpu
