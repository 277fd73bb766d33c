# Sourced by the bench scripts: strict mode, the repository root as working directory, and
# LOOM = the loom binary (default: that of BUILD, default build-bench), which must exist.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${BUILD:-$ROOT/build-bench}"
LOOM="${LOOM:-$BUILD/apps/loom}"
cd "$ROOT"
[ -x "$LOOM" ] || { echo "build loom first: cmake -S . -B build-bench -G Ninja -DCMAKE_BUILD_TYPE=Release && ninja -C build-bench loom" >&2; exit 2; }

# The smaller of two numbers, the second possibly empty (a minimum not yet set):
# best[$k]=$(min_of "$ms" "${best[$k]:-}")
min_of() { awk -v a="$1" -v b="${2:-}" 'BEGIN { print (b == "" || a + 0 < b + 0) ? a : b }'; }
