#!/usr/bin/env bash
# Builds the libFuzzer harnesses (fuzz/, clang + ASan + UBSan) into build-fuzz/ and runs each
# for a bounded time on its seed corpus, two at a time. Prints one row per harness (executions,
# exec/s, coverage edges and features, corpus size, findings) and exits 1 if any harness found
# a crash, a leak, a sanitizer report, a non-UserError exception or an input slower than 10 s.
#
#   tools/fuzz.sh [--seconds N] [--runs N] [--jobs J] [--seed S] [--build DIR] [--out DIR]
#                 [--build-only] [HARNESS...]
#                 (defaults: 60 s, 2 jobs, a random seed, build-fuzz/, out/fuzz/, all seven)
#
# --build-only builds the harnesses and stops (ctest builds them in a test of its own, beside the
# other tests, and fuzzes in a serial one).
#
# --seed fixes libFuzzer's random seed (ctest passes 1): a failing CI run then replays here
# with the same command, the seed printed in its table.
#
# Working corpora grow in OUT/corpus/<harness>; findings land in OUT/findings/.
# A finding becomes a regression test in tests/badinput (see fuzz/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=60
runs=-1
jobs=2
fuzz_seed=0
build=build-fuzz
out=out/fuzz
harnesses=()
build_only=0
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --seed) fuzz_seed=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --build-only) build_only=1; shift ;;
    -h|--help) sed -n 2,17p "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option '$1'" >&2; exit 2 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
all=(graph_json scene_json mitsuba_xml obj gltf lua_json image)
[ ${#harnesses[@]} -eq 0 ] && harnesses=("${all[@]}")
for h in "${harnesses[@]}"; do
  [[ " ${all[*]} " == *" $h "* ]] || { echo "fuzz.sh: unknown harness '$h' (${all[*]})" >&2; exit 2; }
done

# Exit 77 (a skip for ctest) when clang or its sanitizer runtimes are missing.
command -v clang++ >/dev/null || { echo "fuzz.sh: needs clang (tools/install-deps.sh installs it)" >&2; exit 77; }
ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1 ||
  { echo "fuzz.sh: needs libclang-rt-14-dev (libFuzzer)" >&2; exit 77; }
if [ ! -f "$build/build.ninja" ]; then
  # -O1 -gline-tables-only: what libFuzzer recommends, and it builds faster than -O2 -g.
  # A unity build halves the instrumented build's CPU time (382 -> 195 s, 2 cores): the sources
  # share their headers' parsing. It needs names in anonymous namespaces to differ across files.
  CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DLOOM_FUZZ=ON -DCMAKE_BUILD_TYPE=None \
    -DCMAKE_CXX_FLAGS="-O1 -gline-tables-only" -DCMAKE_C_FLAGS="-O1 -gline-tables-only" \
    -DCMAKE_UNITY_BUILD=ON -DLOOM_BUILD_TESTS=OFF -DLOOM_BUILD_BENCH=OFF >/dev/null
fi
targets=()
for h in "${harnesses[@]}"; do targets+=("fuzz_$h"); done
cmake --build "$build" --target "${targets[@]}" | tail -1
[ "$build_only" = 1 ] && exit 0

# Seed corpora: fuzz/seeds/<harness> (formats the project keeps no files of), the project's own
# files of each format, and ../shared/scenes where present.
seeds() {
  local h=$1 dir=$out/seeds/$1
  rm -rf "$dir" && mkdir -p "$dir"
  local pattern
  case "$h" in
    graph_json) pattern='graphs/*.json tests/data/*.json' ;;
    scene_json) pattern='scenes/*.json' ;;
    mitsuba_xml) pattern='scenes/*.xml tests/data/*.xml ../shared/scenes/*/*.xml' ;;
    obj) pattern='scenes/*.obj tests/data/*.obj ../shared/scenes/*/*.obj' ;;
    gltf) pattern='scenes/*.gltf tests/data/*.gltf' ;;
    lua_json) pattern='graphs/*.json scenes/*.json' ;;
    image) pattern='tests/data/*.png tests/data/*.exr' ;;
  esac
  local n=0 f
  for f in fuzz/seeds/$h/* $pattern; do
    [ -f "$f" ] || continue
    # Large meshes slow every execution down without adding syntax.
    [ "$(stat -c %s "$f")" -le 262144 ] || continue
    cp "$f" "$dir/$n-$(basename "$f")"
    n=$((n + 1))
  done
  echo "$dir"
}

mkdir -p "$out/findings" "$out/logs"
run_one() {
  local h=$1 seed corpus=$out/corpus/$1
  seed=$(seeds "$h")
  mkdir -p "$corpus"
  local dict=() d=fuzz/$h.dict
  [ "$h" = lua_json ] && d=fuzz/graph_json.dict
  [ -f "$d" ] && dict=(-dict="$d")
  "$build/fuzz/fuzz_$h" "$corpus" "$seed" "${dict[@]}" -max_total_time="$seconds" \
    -runs="$runs" -seed="$fuzz_seed" -timeout=10 -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$out/findings/$h-" >"$out/logs/$h.log" 2>&1 || true
}
export -f run_one seeds
export seconds runs fuzz_seed build out

printf '%s\n' "${harnesses[@]}" | xargs -P "$jobs" -I{} bash -c 'run_one {}'

status=0
echo "libFuzzer seed: $fuzz_seed (0: random; replay with --seed $fuzz_seed --seconds $seconds)"
printf '| harness | executions | exec/s | coverage (edges) | features | corpus | findings |\n'
printf '| --- | --- | --- | --- | --- | --- | --- |\n'
for h in "${harnesses[@]}"; do
  log=$out/logs/$h.log
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo ?)
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo ?)
  last=$(grep -E "^#[0-9]+" "$log" | tail -1 || true)
  cov=$(echo "$last" | grep -o 'cov: [0-9]*' | grep -o '[0-9]*' || echo ?)
  ft=$(echo "$last" | grep -o 'ft: [0-9]*' | grep -o '[0-9]*' || echo ?)
  corp=$(ls "$out/corpus/$h" | wc -l)
  found=$(ls "$out/findings" 2>/dev/null | grep -c "^$h-" || true)
  if grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error:|not a UserError|Test unit written' "$log"; then
    status=1
  elif ! grep -qE '^Done [0-9]+ runs' "$log"; then
    echo "fuzz.sh: $h did not run to the end: $(tail -n 3 "$log")" >&2
    status=1
  fi
  printf '| %s | %s | %s | %s | %s | %s | %s |\n' "$h" "$execs" "$rate" "$cov" "$ft" "$corp" "$found"
done
if [ $status -ne 0 ]; then
  echo "fuzz.sh: findings (logs in $out/logs, inputs in $out/findings):" >&2
  grep -lE 'ERROR: |runtime error:|not a UserError|Test unit written' "$out"/logs/*.log >&2 || true
  for f in "$out"/findings/*; do [ -f "$f" ] && { echo "--- $f" >&2; tail -n 30 "$out/logs/$(basename "$f" | cut -d- -f1)"*.log >&2; }; done
fi
exit $status
