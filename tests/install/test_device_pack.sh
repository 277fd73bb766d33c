#!/usr/bin/env bash
# tools/device-pack.sh makes a pack under 64 MiB whose libraries are complete (every library
# loom loads, glibc's aside, resolves into the pack), and the pack's run.sh renders with its
# own loom and libraries on this machine's device (lavapipe in CI).
#   test_device_pack.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1 build=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bash "$src/tools/device-pack.sh" --build "$build" --out "$work/pack"
for f in README run.sh bin/loom lib.tar.xz share/loom/bench/device_suite.sh \
         share/loom/graphs/pt.json share/loom/shaders/lib/integrator/nee.glsl; do
  [ -e "$work/pack/$f" ] || { echo "not in the pack: $f"; exit 1; }
done
grep -q "run.sh" "$work/pack/README" || { echo "the README does not say what to run"; exit 1; }

export LOOM_PACK_LIB=$work/lib LOOM_CACHE_DIR=$work/cache LOOM_LOG=warning TMPDIR=$work
(cd "$work" && bash pack/run.sh --check >"$work/check.log" 2>&1) ||
  { echo "run.sh --check failed:"; cat "$work/check.log"; exit 1; }
grep -q "^0: " "$work/check.log" || { echo "run.sh listed no device"; cat "$work/check.log"; exit 1; }
[ -s "$work/loom-pack-check.png" ] || { echo "run.sh --check wrote no image"; exit 1; }

# Every library but glibc's comes from the pack (libstdc++ and libgcc_s from its fallback).
bad=$(LD_LIBRARY_PATH=$work/lib:$work/lib/fallback ldd "$work/pack/bin/loom" |
  awk '$2 == "=>" {print $1, $3}' |
  grep -v -E '^(libc|libm|libdl|libpthread|librt)\.so' | grep -v " $work/lib/" || true)
[ -z "$bad" ] || { echo "libraries loom loads from outside the pack:"; echo "$bad"; exit 1; }
echo "device pack: $(du -sh "$work/pack" | cut -f1), run.sh --check rendered with the packed loom"
