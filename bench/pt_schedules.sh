#!/usr/bin/env bash
# PathTracer's two schedules side by side (issue 22): the megakernel (one invocation runs a
# pixel's whole path) against the wavefront (a dispatch per bounce over the compacted list of
# living paths, shadow rays in dispatches of their own, the last bounce dispatch running what is
# left to the end), at several wavefrontDepth values. Both render the same image bit for bit on
# lavapipe (PathTracer.WavefrontScheduleRendersTheMegakernelsImage), so only time is compared:
# PT GPU ms per frame (loom --timings, first frame excluded), the minimum over REPS interleaved
# repetitions (the machine's noise is one-sided), and Mrays/s at that time. Never asserts.
#
#   bash bench/pt_schedules.sh                         # 128x128, 64 bounces, 24 frames, 5 reps
#   REPS=2 FRAMES=8 WIDTH=64 HEIGHT=64 bash bench/pt_schedules.sh
#
# Scenes: the peer benchmark's two (bench/data/peer), the project's Cornell box and, when
# ../shared/scenes exists, Veach Ajar. Run on an idle machine and report `uptime`.
source "$(dirname "$0")/lib.sh"
W=${WIDTH:-128} H=${HEIGHT:-128} FRAMES=${FRAMES:-24} REPS=${REPS:-5} BOUNCES=${BOUNCES:-64}
OUT=${OUT:-out/pt_schedules}
CONFIGS=${CONFIGS:-"megakernel wavefront:0 wavefront:4 wavefront:8 wavefront:16"}
SCENES=${SCENES:-"bench/data/peer/cornell_grey.json bench/data/peer/glossy_env.json scenes/cornell_box.json"}
[ -f ../shared/scenes/veach-ajar/scene.xml ] && [ -z "${NO_SHARED:-}" ] && SCENES="$SCENES ../shared/scenes/veach-ajar/scene.xml"
mkdir -p "$OUT"
export LP_NUM_THREADS=${THREADS:-2}

run() {  # scene config -> "ms rays_per_frame"
  local schedule=${2%%:*} depth=${2#*:}
  [ "$depth" = "$2" ] && depth=8
  "$LOOM" render graphs/pt.json --scene "$1" --width "$W" --height "$H" --frames "$FRAMES" \
    --set pt.maxBounces="$BOUNCES" --set pt.schedule="$schedule" --set pt.wavefrontDepth="$depth" \
    --timings --quiet --out "$OUT/last.exr" >"$OUT/last.log" 2>&1 \
    || { echo "pt_schedules.sh: render failed: $(tail -3 "$OUT/last.log")" >&2; exit 1; }
  awk '$1 == "pt" && NF == 2 {ms = $2} $1 == "pt" && $2 == "rays" {gsub("[(]", "", $5); r = $5} END {print ms, r}' "$OUT/last.log"
}

echo "pt_schedules: ${W}x${H}, $BOUNCES bounces, $FRAMES frames, min of $REPS interleaved reps, $LP_NUM_THREADS threads; $(uptime)"
csv=$OUT/pt_schedules.csv
echo "scene,config,pt_ms,rays_per_frame,mrays_per_s,speedup_vs_megakernel" >"$csv"
printf '| scene | %s |\n| --- |' "$(echo $CONFIGS | sed 's/ / | /g')"
for c in $CONFIGS; do printf ' --- |'; done
echo
for s in $SCENES; do
  declare -A best=() rays=()
  for ((r = 0; r < REPS; ++r)); do
    for c in $CONFIGS; do
      read -r ms n < <(run "$s" "$c")
      best[$c]=$(min_of "$ms" "${best[$c]:-}")
      rays[$c]=$n
    done
  done
  row="| $(basename "$(dirname "$s")")/$(basename "$s")"
  first=$(echo $CONFIGS | cut -d' ' -f1)
  for c in $CONFIGS; do
    row="$row | $(awk -v t="${best[$c]}" -v b="${best[$first]}" 'BEGIN { printf "%.2f ms (%.2fx)", t, b / t }')"
    awk -v s="$s" -v c="$c" -v t="${best[$c]}" -v n="${rays[$c]}" -v b="${best[$first]}" \
      'BEGIN { printf "%s,%s,%.3f,%d,%.3f,%.4f\n", s, c, t, n, n / t / 1000, b / t }' >>"$csv"
  done
  echo "$row |"
  unset best rays
done
echo "(ms: PT GPU ms per frame; in brackets: speed-up over the first config)"
echo "CSV: $csv"
