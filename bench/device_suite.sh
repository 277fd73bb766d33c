#!/usr/bin/env bash
# Everything worth timing on a GPU device, in one bounded call: every family's graph at
# 1920x1080 (GPU ms per pass, wall ms per frame, Mrays/s of the passes that count rays), the
# PT vs ReSTIR PT equal-time relMSE comparison of bench/restir_equal_time.sh, and BVH traversal
# throughput, and the animated pool of MNEE with dimension reduction at 960x720, on the device
# `loom devices` lists first. Reservoir splatting (splat, splat +
# backup, multi-splat motion blur, Area ReSTIR beside them) runs on scenes/fine_geometry.json,
# whose camera moves: the paper's 1920x1080 GPU setting; the Poisson solvers (L2 by 50 CG steps and
# by 4 multigrid-CG steps, L1 by 20 x 50) on graphs/poisson_pt.json. Prints one markdown table (plus the
# equal-time summary) and writes CSV to out/device_suite/. Each step has its own time limit;
# on a GPU each render step is cut at STEP_S = 40 s, so 20 renders, the equal-time run and the
# BVH bench bound the whole.
#
#   bash bench/device_suite.sh            # on device 0 at 1920x1080
#   bash bench/device_suite.sh --smoke    # 64x64 on lavapipe, project scenes (CI runs this)
#
# LOOM (default BUILD/apps/loom, BUILD default build-bench) names the binary; OUT the output
# folder. Veach Ajar and the SMS sphere come from ../shared/scenes (or scenes/ next to the
# binary in a device pack, tools/device-pack.sh); without them the project's own scenes stand in.
source "$(dirname "$0")/lib.sh"

smoke=0
for a in "$@"; do
  case "$a" in
    --smoke) smoke=1 ;;
    -h|--help) sed -n 2,14p "$0"; exit 0 ;;
    *) echo "device_suite.sh: unknown option '$a'" >&2; exit 2 ;;
  esac
done
OUT=${OUT:-out/device_suite}
mkdir -p "$OUT"
if [ $smoke -eq 1 ]; then
  W=64 H=64 FRAMES=3 STEP_S=300 device=() ET_ARGS=(width=64 height=64 budget_ms=300 steps=2
    move_frames=4 repeats=1 ref_frames=2 ref_spp=4 cameras=static,moving
    scenes=scenes/glossy_spheres.json)
  SHARED_SCENES=${SHARED_SCENES:-none}  # the project's small scenes: the smoke checks the script
else
  W=1920 H=1080 FRAMES=6 STEP_S=40 device=(--device 0) ET_ARGS=(width=1920 height=1080
    budget_ms=3000 steps=3 move_frames=16 repeats=2 ref_frames=16 ref_spp=16)
fi

scene_of() {  # the first of the candidates that exists
  for s in "$@"; do [ -e "$s" ] && { echo "$s"; return; }; done
}
shared=${SHARED_SCENES:-../shared/scenes}
[ -d "$shared" ] || shared=scenes/shared
ajar=$(scene_of "$shared/veach-ajar/scene.xml" scenes/glossy_spheres.json)
sphere=$(scene_of "$shared/sms-sphere/sphere_sms.xml" scenes/glass_sphere.json)
slab=$(scene_of scenes/wavy_slab.json)
fine=$(scene_of scenes/fine_geometry.json)  # its camera moves: temporal reuse under motion
pool=$(scene_of scenes/water_pool_animated.json)  # MNEE with dimension reduction

device_name=$("$LOOM" devices | head -1)
echo "device suite: ${device_name} (${W}x${H}, $(date -u +%Y-%m-%dT%H:%MZ))"
[ $smoke -eq 1 ] || uptime

cornell=$(scene_of scenes/cornell_box.json)

# config name | graph | scene | extra render arguments (optional)
configs=(
  "pt|graphs/pt.json|$ajar"
  "pt_wavefront|graphs/pt.json|$ajar|--set pt.schedule=wavefront"
  "pt_cornell|graphs/pt.json|$cornell"
  "pt_cornell_wavefront|graphs/pt.json|$cornell|--set pt.schedule=wavefront"
  "restir_pt|graphs/restir_pt.json|$ajar"
  "area_restir|graphs/area_restir.json|$ajar"
  "sms|graphs/sms.json|$sphere"
  "sms_biased|graphs/sms_biased.json|$sphere"
  "mnee|graphs/mnee.json|$sphere"
  "sms_slab|graphs/sms.json|$slab"
  "psms_slab|graphs/psms.json|$slab"
  "psms_restir_slab|graphs/psms_restir.json|$slab"
  "mnee_dr_pool|graphs/mnee_dr.json|$pool"
  "area_restir_fine|graphs/area_restir.json|$fine"
  "splat|graphs/splat.json|$fine"
  "splat_backup|graphs/splat_backup.json|$fine"
  "splat_motion_blur|graphs/splat_motion_blur.json|$fine"
  "poisson_l2_cg50|graphs/poisson_pt.json|$cornell|--set poisson.iterations=50"
  "poisson_l2_mg4|graphs/poisson_pt.json|$cornell|--set poisson.linearSolver=multigrid --set poisson.iterations=4"
  "poisson_l1_cg20x50|graphs/poisson_pt.json|$cornell|--set poisson.solver=l1"
)

passes_csv=$OUT/passes.csv
frames_csv=$OUT/frames.csv
echo "config,graph,scene,width,height,pass,gpu_ms" >"$passes_csv"
echo "config,graph,scene,width,height,frames,gpu_ms,wall_ms,mrays_per_s,status" >"$frames_csv"
table="| config | scene | GPU ms/frame | wall ms/frame | Mrays/s | passes (GPU ms) |
| --- | --- | --- | --- | --- | --- |"
for c in "${configs[@]}"; do
  IFS='|' read -r name graph scene extra <<<"$c"
  read -r -a extra_args <<<"${extra:-}"
  [ -n "$scene" ] || continue
  log=$OUT/$name.log
  status=ok
  timeout "$STEP_S" "$LOOM" render "$graph" --scene "$scene" --width "$W" --height "$H" \
    --frames "$FRAMES" --timings --quiet "${device[@]}" ${extra_args[@]+"${extra_args[@]}"} \
    --out "$OUT/$name.png" >"$log" 2>&1 ||
    status="failed ($?)"
  # The --timings table: "pass  ms" lines up to "total (GPU)", then "frame (wall)", then rays.
  awk -v cfg="$name" -v g="$graph" -v s="$scene" -v w="$W" -v h="$H" '
    /^pass +GPU ms/ { on = 1; next }
    on && /^total \(GPU\)/ { on = 0; next }
    on && NF == 2 { printf "%s,%s,%s,%s,%s,%s,%s\n", cfg, g, s, w, h, $1, $2 }' "$log" >>"$passes_csv"
  gpu=$(awk '/^total \(GPU\)/ {print $3}' "$log")
  wall=$(awk '/^frame \(wall\)/ {print $3}' "$log")
  mrays=$(awk '/ rays +[0-9.]+ Mrays\/s/ {s += $3} END {if (s > 0) printf "%.1f", s}' "$log")
  breakdown=$(awk '/^pass +GPU ms/ {on = 1; next} on && /^total/ {on = 0}
    on && NF == 2 {printf "%s%s %s", sep, $1, $2; sep = ", "}' "$log")
  echo "$name,$graph,$scene,$W,$H,$FRAMES,${gpu:-},${wall:-},${mrays:-},$status" >>"$frames_csv"
  [ "$status" = ok ] || breakdown="$status: $(tail -n 1 "$log")"
  table+="
| $name | $(basename "$(dirname "$scene")")/$(basename "$scene") | ${gpu:--} | ${wall:--} | ${mrays:--} | $breakdown |"
done

# BVH traversal alone: closest-hit rays of the path tracer's first bounce on Veach Ajar.
bvh_log=$OUT/bvh.log
timeout "$STEP_S" "$LOOM" render graphs/pt.json --scene "$ajar" --width "$W" --height "$H" \
  --frames "$FRAMES" --timings --quiet "${device[@]}" --set pt.maxBounces=1 \
  --out "$OUT/bvh.png" >"$bvh_log" 2>&1 || true
bvh=$(awk '/ rays +[0-9.]+ Mrays\/s/ {print $3; exit}' "$bvh_log")

# The animated pool at the paper's 960x720 (Granizo-Hidalgo & Holzschuch 2024: under 25 ms per
# frame on an RTX A4000): the water re-tessellated every frame, GPU ms per frame.
pool_status=ok
PW=$([ $smoke -eq 1 ] && echo 64 || echo 960) PH=$([ $smoke -eq 1 ] && echo 48 || echo 720)
LOOM_DEVICE=$([ $smoke -eq 1 ] && echo "" || echo 0) timeout "$STEP_S" \
  "$LOOM" run --quiet scripts/water_caustics.lua width="$PW" height="$PH" steps=4 frames=2 \
  out="$OUT/water_caustics" >"$OUT/water_caustics.log" 2>&1 || pool_status="failed ($?)"

# Equal-time relMSE, PT vs ReSTIR PT (the script of bench/restir_equal_time.sh).
et_status=ok
LOOM_DEVICE=$([ $smoke -eq 1 ] && echo "" || echo 0) timeout $((STEP_S * 4)) \
  "$LOOM" run --quiet scripts/restir_equal_time.lua "${ET_ARGS[@]}" out="$OUT/equal_time" \
  >"$OUT/equal_time.log" 2>&1 || et_status="failed ($?)"

echo
echo "$table"
echo
echo "BVH traversal (pt.maxBounces=1): ${bvh:--} Mrays/s"
echo
echo "Animated pool, MNEE with dimension reduction, ${PW}x${PH} ($pool_status):"
grep -A8 "^step" "$OUT/water_caustics.log" || tail -n 3 "$OUT/water_caustics.log"
echo
echo "Equal time, PT vs ReSTIR PT ($et_status):"
if [ -f "$OUT/equal_time/summary.csv" ]; then
  awk -F, 'NR == 1 {for (i = 1; i <= NF; i++) col[$i] = i; print "| scene | camera | config | relMSE |"; print "| --- | --- | --- | --- |"; next}
    {printf "| %s | %s | %s | %s |\n", $col["scene"], $col["camera"], $col["config"], $col["relmse"]}' \
    "$OUT/equal_time/summary.csv"
else
  tail -n 5 "$OUT/equal_time.log"
fi
echo
echo "CSV: $frames_csv, $passes_csv, $OUT/equal_time/summary.csv"
failed=$(grep -c ',failed' "$frames_csv" || true)
[ "$failed" -eq 0 ] && [ "$et_status" = ok ] && [ "$pool_status" = ok ] ||
  { echo "device suite: $failed config(s) failed, equal time $et_status, pool $pool_status" >&2; exit 1; }
