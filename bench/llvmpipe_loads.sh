#!/usr/bin/env bash
# What a load costs on llvmpipe (issue 22, "memory traffic"): dependent loads at hashed
# addresses from the scene's BVH triangle records (a storage buffer) or node image, by the form
# of the load (bench/data/llvmpipe/
# load_cost.comp: one float, one vec4, a 32-byte struct of two vec4s, the same 32 bytes as one
# u64vec4 or as eight floats, a vec4 every invocation shares, an RGBA32UI image texel), over a
# small working set (COUNT_SMALL records: caches) and a large one (COUNT_LARGE, capped at the
# scene's triangle count). Prints GPU ms per dispatch (min over REPS) and ns per load instruction
# of an 8-lane SIMD batch, the loop and hash alone subtracted. Never asserts.
#
#   bash bench/llvmpipe_loads.sh                 # 256x256, 200 loads, 1 llvmpipe thread
#   SCENE=../shared/scenes/veach-ajar/scene.xml bash bench/llvmpipe_loads.sh
source "$(dirname "$0")/lib.sh"
W=${WIDTH:-256} H=${HEIGHT:-256} STEPS=${STEPS:-200} FRAMES=${FRAMES:-5} REPS=${REPS:-3}
SCENE=${SCENE:-bench/data/peer/glossy_env.json}
COUNT_SMALL=${COUNT_SMALL:-1000} COUNT_LARGE=${COUNT_LARGE:-100000000}
OUT=${OUT:-out/llvmpipe_loads}
mkdir -p "$OUT"
export LP_NUM_THREADS=${THREADS:-1}
export LOOM_SHADER_PATH=$ROOT/bench/data/llvmpipe${LOOM_SHADER_PATH:+:$LOOM_SHADER_PATH}

labels=("nothing (loop and hash)" "float" "vec4" "struct of two vec4 (32 B)" "u64vec4 (32 B)"
  "eight floats (32 B)" "vec4, one address for all" "imageLoad, RGBA32UI texel")
kernel_ms() {  # form count -> GPU ms per dispatch (first frame excluded)
  "$LOOM" render bench/data/llvmpipe/load_cost.json --scene "$SCENE" --width "$W" --height "$H" \
    --frames "$FRAMES" --set kernel.steps="$STEPS" --set kernel.count="$2" \
    --set "kernel.defines={\"FORM\": \"$1\"}" --timings --quiet --out "$OUT/last.exr" \
    >"$OUT/last.log" 2>&1 || { echo "llvmpipe_loads.sh: render failed: $(tail -3 "$OUT/last.log")" >&2; exit 1; }
  awk '$1 == "kernel" && NF == 2 {print $2}' "$OUT/last.log"
}
declare -A best
for ((r = 0; r < REPS; ++r)); do
  for c in "$COUNT_SMALL" "$COUNT_LARGE"; do
    for f in 0 1 2 3 4 5 6 7; do
      ms=$(kernel_ms "$f" "$c")
      [ -n "$ms" ] || { echo "llvmpipe_loads.sh: no 'kernel' timing in $OUT/last.log" >&2; exit 1; }
      k="$c $f"
      best[$k]=$(min_of "$ms" "${best[$k]:-}")
    done
  done
done
echo "llvmpipe_loads: $SCENE, ${W}x${H}, $STEPS loads per invocation, LP_NUM_THREADS=$LP_NUM_THREADS, $REPS reps (min); $(uptime)"
printf '\n| load | %s records: GPU ms | ns per batch load | %s records: GPU ms | ns per batch load |\n| --- | --- | --- | --- | --- |\n' "$COUNT_SMALL" "$COUNT_LARGE"
csv=$OUT/llvmpipe_loads.csv
echo "form,load,small_ms,small_ns,large_ms,large_ns" >"$csv"
for f in 0 1 2 3 4 5 6 7; do
  awk -v l="${labels[$f]}" -v f="$f" -v a="${best[$COUNT_SMALL $f]}" -v a0="${best[$COUNT_SMALL 0]}" \
      -v b="${best[$COUNT_LARGE $f]}" -v b0="${best[$COUNT_LARGE 0]}" -v n="$((W * H / 8 * STEPS))" -v csv="$csv" 'BEGIN {
    x = 1e6 * (a - a0) / n; y = 1e6 * (b - b0) / n
    printf "| %s | %.2f | %.1f | %.2f | %.1f |\n", l, a, x, b, y
    printf "%d,%s,%.3f,%.2f,%.3f,%.2f\n", f, l, a, x, b, y >> csv }'
done
echo "CSV: $csv"
