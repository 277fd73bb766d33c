#!/usr/bin/env bash
# What a branch costs on llvmpipe (issue 22): a fixed block of ALU work (bench/data/llvmpipe/
# branch_cost.comp, STEPS dependent sin/cos iterations) run by nobody, by everybody, behind a
# uniform false branch, behind a per-invocation false branch, by every other invocation
# (divergent inside each SIMD batch) and by every other batch of 8 (coherent), once as a loop
# (STEPS iterations) and once as straight-line code (128 unrolled iterations). Prints GPU ms per
# dispatch (min over REPS) and each case's cost as a share of "every invocation runs it".
# Never asserts.
#
#   bash bench/llvmpipe_costs.sh                  # 256x256, 200 steps, 1 llvmpipe thread
#   THREADS=2 STEPS=400 bash bench/llvmpipe_costs.sh
source "$(dirname "$0")/lib.sh"
W=${WIDTH:-256} H=${HEIGHT:-256} STEPS=${STEPS:-200} FRAMES=${FRAMES:-9} REPS=${REPS:-3}
OUT=${OUT:-out/llvmpipe_costs}
mkdir -p "$OUT"
export LP_NUM_THREADS=${THREADS:-1}
export LOOM_SHADER_PATH=$ROOT/bench/data/llvmpipe${LOOM_SHADER_PATH:+:$LOOM_SHADER_PATH}

labels=("nobody (no branch)" "every invocation (no branch)" "nobody, uniform false branch"
  "nobody, per-invocation false branch" "every other invocation (divergent in a batch)"
  "every other batch of 8 (coherent)")
kernel_ms() {  # work shape -> GPU ms per dispatch (first frame excluded)
  "$LOOM" render bench/data/llvmpipe/branch_cost.json --width "$W" --height "$H" --frames "$FRAMES" \
    --set kernel.work="$1" --set kernel.steps="$STEPS" --set "kernel.defines={\"BLOCK_SHAPE\": \"$2\", \"WORK\": \"$1\"}" \
    --timings --quiet --out "$OUT/last.exr" \
    >"$OUT/last.log" 2>&1 || { echo "llvmpipe_costs.sh: render failed: $(tail -3 "$OUT/last.log")" >&2; exit 1; }
  awk '$1 == "kernel" && NF == 2 {print $2}' "$OUT/last.log"
}
declare -A best
for ((r = 0; r < REPS; ++r)); do
  for shape in 0 1; do
    for w in 0 1 2 3 4 5; do
      ms=$(kernel_ms "$w" "$shape")
      [ -n "$ms" ] || { echo "llvmpipe_costs.sh: no 'kernel' timing in $OUT/last.log" >&2; exit 1; }
      k="$shape $w"
      best[$k]=$(min_of "$ms" "${best[$k]:-}")
    done
  done
done
echo "llvmpipe_costs: ${W}x${H}, $STEPS steps, LP_NUM_THREADS=$LP_NUM_THREADS, $REPS reps (min); $(uptime)"
printf '\n| who runs the block | loop: GPU ms | share | straight-line: GPU ms | share |\n| --- | --- | --- | --- | --- |\n'
csv=$OUT/llvmpipe_costs.csv
echo "work,case,loop_ms,loop_share,straight_ms,straight_share" >"$csv"
for w in 0 1 2 3 4 5; do
  awk -v l="${labels[$w]}" -v t="${best[0 $w]}" -v z="${best[0 0]}" -v a="${best[0 1]}" \
      -v u="${best[1 $w]}" -v y="${best[1 0]}" -v c="${best[1 1]}" -v w="$w" -v csv="$csv" 'BEGIN {
    s = (t - z) / (a - z); q = (u - y) / (c - y)
    printf "| %s | %.2f | %.0f%% | %.2f | %.0f%% |\n", l, t, 100 * s, u, 100 * q
    printf "%d,%s,%.3f,%.4f,%.3f,%.4f\n", w, l, t, s, u, q >> csv }'
done
echo "CSV: $csv"
