#!/usr/bin/env bash
# Loom's path tracer beside Blender Cycles on the CPU, on the same scenes (issue 22): the peer
# scenes of bench/data/peer (world-space OBJ parts both renderers read: a grey Cornell box with
# one area light, and glossy spheres under a constant environment and an area light), built in
# Blender through its Python API (bench/peer_cycles.py) and rendered by Cycles with 2 threads,
# box filter, no denoising, no clamping, Standard view transform, EXR. Prints, per scene and
# renderer: ms per sample per image, measured the same way for both: one render of SPP samples
# and one of 1 sample, (time(SPP) - time(1)) / (SPP - 1), which removes scene loading, BVH build
# and kernel setup (Loom: `loom render --frames 1 --set pt.samplesPerPixel=SPP`, whole process
# wall time); for Loom also its interactive rate, ms per frame at 1 sample per frame (the first
# frame left out); and relMSE at SPP samples against a REF_SPP reference of each renderer
# (variance) and of Cycles (variance plus any difference between the renderers), and the ratio
# of the two references' means, and Loom's time to Cycles' error. Loom renders once per
# PathTracer sampler in SAMPLERS (default "independent sobol"; the reference is independent's).
# Timings are the minimum over REPS (default 3) interleaved repetitions. Never asserts. Skips
# when Blender is absent.
#
#   bash bench/peer_cycles.sh                      # 128x128, 64 spp, 64 bounces, 2048-spp references
#   SPP=16 REF_SPP=256 WIDTH=64 HEIGHT=64 bash bench/peer_cycles.sh    # quicker
#
# Run it on an idle machine (both renderers use THREADS cores, default 2) and report `uptime`.
# References are cached in OUT (default out/peer_cycles) by scene, size, bounces and spp.
source "$(dirname "$0")/lib.sh"
command -v blender >/dev/null || { echo "peer_cycles.sh: skipped: Blender is not installed (apt-get install blender)"; exit 0; }

W=${WIDTH:-128} H=${HEIGHT:-128} SPP=${SPP:-64} REF_SPP=${REF_SPP:-2048}
THREADS=${THREADS:-2} BOUNCES=${BOUNCES:-64} OUT=${OUT:-out/peer_cycles} REPS=${REPS:-3}
SCENES=${SCENES:-"cornell_grey glossy_env"}
SAMPLERS=${SAMPLERS:-"independent sobol"}  # PathTracer.sampler values, one Loom row each
mkdir -p "$OUT"
export LP_NUM_THREADS=$THREADS WIDTH=$W HEIGHT=$H

cycles() {  # scene spp out.exr seed -> prints render seconds
  blender -b --factory-startup --python bench/peer_cycles.py -- "bench/data/peer/$1.json" "$2" \
    "$3" "$THREADS" "$BOUNCES" "$4" >"$3.log" 2>&1 || { echo "Cycles failed: $(tail -3 "$3.log")" >&2; exit 1; }
  sed -n 's/^peer_cycles: render_s=\([0-9.]*\).*/\1/p' "$3.log"
}
loom_pt() {  # scene spp out.exr seed [sampler] -> prints wall seconds of the whole render (spp in one frame)
  local t0 t1
  t0=$(date +%s.%N)
  "$LOOM" render graphs/pt.json --scene "bench/data/peer/$1.json" --width "$W" --height "$H" \
    --frames 1 --seed "$4" --set pt.maxBounces="$BOUNCES" --set pt.samplesPerPixel="$2" \
    --set pt.sampler="\"${5:-independent}\"" \
    --quiet --out "$3" >"$3.log" 2>&1 || { echo "Loom failed: $(tail -3 "$3.log")" >&2; exit 1; }
  t1=$(date +%s.%N)
  awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.4f", b - a}'
}
loom_interactive() {  # scene frames sampler -> prints wall ms per frame at 1 sample per frame
  "$LOOM" render graphs/pt.json --scene "bench/data/peer/$1.json" --width "$W" --height "$H" \
    --frames "$2" --set pt.maxBounces="$BOUNCES" --set pt.samplesPerPixel=1 --set pt.sampler="\"$3\"" \
    --timings --quiet --out "$OUT/interactive.exr" >"$OUT/interactive.log" 2>&1 || { echo "Loom failed: $(tail -3 "$OUT/interactive.log")" >&2; exit 1; }
  awk '/^frame \(wall\)/ {print $3}' "$OUT/interactive.log"
}
per_sample() {  # seconds of a 1-sample and an SPP-sample render -> ms per sample
  awk -v a="$1" -v b="$2" -v n="$SPP" 'BEGIN {printf "%.2f", 1000 * (b - a) / (n - 1)}'
}
compare() { "$LOOM" run bench/peer_compare.lua image="$1" ref="$2"; }

echo "peer_cycles: ${W}x${H}, $SPP spp, $BOUNCES bounces, references $REF_SPP spp, $THREADS threads; $(blender --version 2>/dev/null | head -1); $(uptime)"
rows="| scene | renderer | ms/sample | ms/frame at 1 spp | relMSE vs own ref | relMSE vs Cycles ref | ref mean / Cycles ref mean | time at equal error / Cycles' |
| --- | --- | --- | --- | --- | --- | --- | --- |"
csv=$OUT/peer_cycles.csv
echo "scene,renderer,width,height,spp,ms_per_sample,ms_per_frame_1spp,relmse_own_ref,relmse_cycles_ref,ref_mean_ratio,time_equal_error_vs_cycles" >"$csv"
for s in $SCENES; do
  tag=${s}_${W}x${H}_b${BOUNCES}
  cref=$OUT/ref_cycles_${tag}_${REF_SPP}.exr lref=$OUT/ref_loom_${tag}_${REF_SPP}.exr
  [ -f "$cref" ] || cycles "$s" "$REF_SPP" "$cref" 1000 >/dev/null
  [ -f "$lref" ] || loom_pt "$s" "$REF_SPP" "$lref" 1000 >/dev/null
  # time(SPP) - time(1) removes scene sync, BVH build and kernel setup; the minimum over REPS
  # interleaved repetitions of each.
  declare -A l_ms=() l_int=()
  c_ms=""
  for smp in $SAMPLERS; do  # compile each sampler's kernels before timing
    loom_pt "$s" 1 "$OUT/loom_${smp}_${tag}_warm.exr" 1 "$smp" >/dev/null
  done
  for ((r = 0; r < REPS; ++r)); do
    t1=$(cycles "$s" 1 "$OUT/cycles_${tag}_1.exr" 1)
    tn=$(cycles "$s" "$SPP" "$OUT/cycles_${tag}_$SPP.exr" 1)
    c_ms=$(min_of "$(per_sample "$t1" "$tn")" "$c_ms")
    for smp in $SAMPLERS; do
      t1=$(loom_pt "$s" 1 "$OUT/loom_${smp}_${tag}_1.exr" 1 "$smp")
      tn=$(loom_pt "$s" "$SPP" "$OUT/loom_${smp}_${tag}_$SPP.exr" 1 "$smp")
      l_ms[$smp]=$(min_of "$(per_sample "$t1" "$tn")" "${l_ms[$smp]:-}")
      l_int[$smp]=$(min_of "$(loom_interactive "$s" "$SPP" "$smp")" "${l_int[$smp]:-}")
    done
  done
  c_own=$(compare "$OUT/cycles_${tag}_$SPP.exr" "$cref")
  refs=$(compare "$lref" "$cref")
  rows+="
| $s | Cycles | $c_ms | | ${c_own%,*} | ${c_own%,*} | 1 | 1 |"
  echo "$s,cycles,$W,$H,$SPP,$c_ms,,${c_own%,*},${c_own%,*},1,1" >>"$csv"
  for smp in $SAMPLERS; do
    img=$OUT/loom_${smp}_${tag}_$SPP.exr
    l_own=$(compare "$img" "$lref")
    l_cyc=$(compare "$img" "$cref")
    eq=$(awk -v lm="${l_ms[$smp]}" -v cm="$c_ms" -v le="${l_own%,*}" -v ce="${c_own%,*}" 'BEGIN {printf "%.2f", lm * le / (cm * ce)}')
    rows+="
| $s | Loom (lavapipe), sampler $smp | ${l_ms[$smp]} | ${l_int[$smp]} | ${l_own%,*} | ${l_cyc%,*} | ${refs#*,} | $eq |"
    echo "$s,loom_$smp,$W,$H,$SPP,${l_ms[$smp]},${l_int[$smp]},${l_own%,*},${l_cyc%,*},${refs#*,},$eq" >>"$csv"
  done
done
echo
echo "$rows"
echo
echo "relMSE of the two references against each other: variance of both plus any systematic"
echo "difference; 'ref mean / Cycles ref mean' is Loom's reference over Cycles'; 'time at equal"
echo "error' is ms/sample x relMSE (own reference) over Cycles' (relMSE falls as 1/spp). CSV: $csv"
