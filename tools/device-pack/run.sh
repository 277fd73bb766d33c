#!/usr/bin/env bash
# The device pack's one command (tools/device-pack.sh made this folder): sets up the packed
# libraries and the NVIDIA Vulkan driver, then runs bench/device_suite.sh with the packed loom.
#   run.sh [--check | device_suite.sh options such as --smoke]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
lib=${LOOM_PACK_LIB:-/tmp/loom-pack/lib}
if [ ! -f "$lib/.from" ] || [ "$(cat "$lib/.from")" != "$here" ]; then
  rm -rf "$lib" && mkdir -p "$(dirname "$lib")"
  if command -v xz >/dev/null; then
    xz -dc "$here/lib.tar.xz"
  else  # no xz-utils: Python's lzma
    python3 -c 'import lzma, sys; sys.stdout.buffer.write(lzma.open(sys.argv[1]).read())' \
      "$here/lib.tar.xz"
  fi | tar -C "$(dirname "$lib")" -xf -
  echo "$here" >"$lib/.from"
fi
# GLIBCXX_3.4.30 is GCC 12's libstdc++, the one the pack was built with. (awk reads all of
# ldconfig's output: an early exit would kill ldconfig with SIGPIPE under pipefail.)
sys_stdcxx=$(ldconfig -p 2>/dev/null | awk '/libstdc\+\+\.so\.6 .*x86-64/ && !p {p = $NF} END {print p}')
path=$lib
if [ -z "$sys_stdcxx" ] || ! grep -qa GLIBCXX_3.4.30 "$sys_stdcxx"; then path=$lib:$lib/fallback; fi
for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib; do [ -d "$d" ] && path=$path:$d; done
export LD_LIBRARY_PATH=$path${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ] && [ -f "$icd" ]; then
  export VK_DRIVER_FILES=$icd
fi
export LOOM=$here/bin/loom
export LOOM_CACHE_DIR=${LOOM_CACHE_DIR:-/tmp/loom-pack/cache}
missing=$(ldd "$LOOM" | grep "not found" || true)
[ -z "$missing" ] || { echo "run.sh: libraries missing on this machine:"; echo "$missing"; exit 2; } >&2
echo "device pack: $(grep '^Packed' "$here/README" || true)"
echo "LD_LIBRARY_PATH=$LD_LIBRARY_PATH${VK_DRIVER_FILES:+ VK_DRIVER_FILES=$VK_DRIVER_FILES}"
"$LOOM" devices || { echo "run.sh: loom sees no Vulkan device (VK_DRIVER_FILES=${VK_DRIVER_FILES:-})" >&2; exit 2; }
data=$here/share/loom
if [ "${1:-}" = --check ]; then
  "$LOOM" render "$data/graphs/pt.json" --scene "$data/scenes/cornell_box.json" --width 32 \
    --height 32 --frames 2 --timings --out "${TMPDIR:-/tmp}/loom-pack-check.png"
  exit
fi
# The suite writes to /tmp/loom-pack/device_suite. Where OUT names a folder (the device tool's
# $OUT), the log, the CSVs and a tarball of everything but the images are copied there: at most
# 8 files come back from a device call.
results=/tmp/loom-pack/device_suite
rm -rf "$results"
set +e
OUT=$results bash "$data/bench/device_suite.sh" "$@" 2>&1 | tee /tmp/loom-pack/suite.log
rc=${PIPESTATUS[0]}
set -e
if [ -n "${OUT:-}" ] && [ -d "$OUT" ]; then
  cp /tmp/loom-pack/suite.log "$OUT/suite.log"
  for f in frames.csv passes.csv; do [ -f "$results/$f" ] && cp "$results/$f" "$OUT/"; done
  [ -f "$results/equal_time/summary.csv" ] && cp "$results/equal_time/summary.csv" "$OUT/equal_time.csv"
  tar -C "$results" --exclude='*.png' --exclude='*.exr' -czf "$OUT/device_suite.tar.gz" .
fi
exit "$rc"
