#pragma once
// Error types shared by every Loom module. Input errors (bad graph, parameter, file, script)
// are UserError: the CLI prints the message and exits with code 2. Everything else is an
// internal error (exit 1).
#include <stdexcept>
#include <string>

namespace loom {

class UserError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class GpuError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// A GPU submit outlived the watchdog's timeout (gpu::Watchdog): a shader that does not
// terminate, or a frame larger than the timeout allows. The message names the pass.
class GpuHang : public UserError {
public:
    using UserError::UserError;
};

}  // namespace loom
