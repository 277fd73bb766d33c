#!/usr/bin/env bash
# Kernels compiled for the scene's material and light types (LOOM_SCENE_MATERIALS and
# LOOM_SCENE_LIGHTS, the Renderer's default) against kernels carrying every type's code
# (LOOM_SCENE_SPECIALIZATION=0), issue 22. llvmpipe (Mesa 22) runs the straight-line code of
# every if-block whether a lane takes it or not, so code for absent types costs time. Both
# render the same image (SceneRender.SceneSpecializationKeepsTheImage); only time is compared:
# GPU ms per frame of each pass (loom --timings, first frame excluded), the minimum over REPS
# interleaved repetitions. Never asserts.
#
#   bash bench/scene_specialization.sh            # PT 128x128 64 bounces; ReSTIR PT 256x256
#   REPS=1 FRAMES=3 PT_SIZE=32 RESTIR_SIZE=32 NO_SHARED=1 bash bench/scene_specialization.sh
source "$(dirname "$0")/lib.sh"
REPS=${REPS:-3} FRAMES=${FRAMES:-12} PT_SIZE=${PT_SIZE:-128} RESTIR_SIZE=${RESTIR_SIZE:-256}
OUT=${OUT:-out/scene_specialization}
mkdir -p "$OUT"
export LP_NUM_THREADS=${THREADS:-2}
ajar=../shared/scenes/veach-ajar/scene.xml
[ -f "$ajar" ] && [ -z "${NO_SHARED:-}" ] || ajar=scenes/glossy_spheres.json
big=$(basename "$ajar" .json); [ "$big" = scene.xml ] && big=veach-ajar
# name | graph | scene | size | extra arguments
RUNS=(
  "pt cornell_grey|graphs/pt.json|bench/data/peer/cornell_grey.json|$PT_SIZE|--set pt.maxBounces=64"
  "pt glossy_env|graphs/pt.json|bench/data/peer/glossy_env.json|$PT_SIZE|--set pt.maxBounces=64"
  "pt cornell_box|graphs/pt.json|scenes/cornell_box.json|$PT_SIZE|--set pt.maxBounces=64"
  "pt $big|graphs/pt.json|$ajar|$PT_SIZE|--set pt.maxBounces=64"
  "restir_pt $big|graphs/restir_pt.json|$ajar|$RESTIR_SIZE|"
)
run() {  # spec graph scene size extra -> "pass ms" lines
  LOOM_SCENE_SPECIALIZATION=$1 "$LOOM" render "$2" --scene "$3" --width "$4" --height "$4" \
    --frames "$FRAMES" $5 --timings --quiet --out "$OUT/last.exr" >"$OUT/last.log" 2>&1 \
    || { echo "scene_specialization.sh: render failed: $(tail -3 "$OUT/last.log")" >&2; exit 1; }
  awk '/^pass +GPU ms/ {on = 1; next} on && NF == 2 {print $1, $2} /^total \(GPU\)/ {on = 0}' "$OUT/last.log"
}
echo "scene_specialization: $FRAMES frames, min of $REPS interleaved reps, $LP_NUM_THREADS threads; $(uptime)"
printf '\n| run | pass | every type (ms) | scene types (ms) | speed-up |\n| --- | --- | --- | --- | --- |\n'
csv=$OUT/scene_specialization.csv
echo "run,pass,all_types_ms,scene_types_ms,speedup" >"$csv"
for r in "${RUNS[@]}"; do
  IFS='|' read -r name graph scene size extra <<<"$r"
  declare -A best=()
  for ((k = 0; k < REPS; ++k)); do
    for spec in 0 1; do
      while read -r pass ms; do
        key="$spec $pass"
        best[$key]=$(min_of "$ms" "${best[$key]:-}")
      done < <(run "$spec" "$graph" "$scene" "$size" "$extra")
    done
  done
  for key in "${!best[@]}"; do
    [ "${key%% *}" = 0 ] || continue
    pass=${key#* }
    a=${best["0 $pass"]} b=${best["1 $pass"]:-}
    [ -n "$b" ] || continue
    awk -v n="$name" -v p="$pass" -v a="$a" -v b="$b" 'BEGIN { if (a >= 2.0) printf "| %s | %s | %.2f | %.2f | %.2fx |\n", n, p, a, b, a / b }'
    awk -v n="$name" -v p="$pass" -v a="$a" -v b="$b" 'BEGIN { printf "%s,%s,%.3f,%.3f,%.4f\n", n, p, a, b, a / b }' >>"$csv"
  done | sort
  unset best
done
echo "(passes under 2 ms left out of the table; all in the CSV)"
echo "CSV: $csv"
