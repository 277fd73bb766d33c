// Enumerations the ReSTIR PT library reads from its buffers (shaders/lib/restir): declared once
// here, they reach every kernel as SHIFT_* and DOF_SHIFT_* defines (ShaderEnums.h).
#include "passes/restir_pt/PathReservoir.h"

namespace loom::restir {

LOOM_REGISTER_SHADER_ENUM(Shift, "SHIFT", {"hybrid", "reconnection", "replay"},
                          "shift mapping of all reuse (Lin et al. 2022, Sec. 6)");
LOOM_REGISTER_SHADER_ENUM(
    DofShift, "DOF_SHIFT", {"both", "copy", "reconnect"},
    "Area ReSTIR primary-vertex shifts under a thin lens (Zhang et al. 2024)");

}  // namespace loom::restir
