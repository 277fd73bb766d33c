#!/usr/bin/env bash
# Reservoir splatting (Liu et al. 2025, Fig. 7): Area ReSTIR fast and robust (gather) against
# splat and splat + backup (scatter), under camera motion, against a high-spp path-traced
# reference: the last single frame of a MOVE_FRAMES-frame dolly (the camera moves in towards
# its target, turns and zooms; it ends on the scene camera, or on the staircase starts there),
# MAPE and relMSE averaged over REPEATS seeds, ms per frame, and the error ratio scaled to
# equal time. Scenes: scenes/fine_geometry.json
# (thin geometry, the paper's foliage/hair stand-in) and, when ../shared/scenes is there, the
# staircase (the paper's wooden staircase). Then motion blur: multi-splatting against the
# naive backprojected baseline at a 4-frame shutter. Then the GPU ms of each stage at 256x256.
# Prints tables; never asserts. BUILD defaults to build-bench.
#
#   bash bench/splat_equal_time.sh                       # 128x128, 8 repeats
#   WIDTH=64 HEIGHT=64 REPEATS=2 STAGE=128 bash bench/splat_equal_time.sh   # quicker
# OUT (default out/splat_equal_time) takes the tables' CSVs and images; STAGE is the stage-timing size.
source "$(dirname "$0")/lib.sh"
uptime
OUT="${OUT:-out/splat_equal_time}"
STAGE="${STAGE:-256}"
# Motion per scene (the camera swings about its look-at point, a scene-dependent distance away).
run() {  # scene, degrees, dolly, out name[, shutter]; MOVE_ZOOM: fov factor at the start
    "$LOOM" run scripts/restir_equal_time.lua configs="${CONFIGS:-bench/data/splat_configs.json}" scenes="$1" \
        cameras=moving move=dolly move_degrees="$2" move_dolly="$3" move_zoom="${MOVE_ZOOM:-1.15}" move_frames="${MOVE_FRAMES:-16}" \
        width="${WIDTH:-128}" height="${HEIGHT:-128}" budget_ms=1 steps=1 repeats="${REPEATS:-8}" \
        ref_frames="${REF_FRAMES:-32}" ref_spp=64 out="$OUT/$4" ${5:+shutter=$5} move_end="${MOVE_END:-scene}"
}
scenes=scenes/fine_geometry.json
run scenes/fine_geometry.json 8 0.15 fine_geometry
stairs=${STAIRS:-../shared/scenes/staircase2-modern-hall/scene.xml}  # STAIRS=none: skip
if [ -e "$stairs" ]; then
    scenes="$scenes $stairs"
    # Its look-at point is 13 units away (2 degrees move the camera 0.45), and a wall is just
    # behind the camera: the dolly starts at the scene camera and moves forward 10 % of the way
    # to the look-at point, where the reference is rendered (move_end = ahead).
    MOVE_END=ahead run "$stairs" 2 0.1 staircase
fi
# Motion blur (Sec. 4.4.1): multi-splatting against the naive backprojected baseline (gather
# with the time copied), both with a 4-frame shutter of the dolly, against a blurred reference.
CONFIGS=bench/data/splat_motion_blur_configs.json run scenes/fine_geometry.json 8 0.15 \
    fine_geometry_motion_blur 0,4
for scene in $scenes; do
    for mode in gather scatter scatter_backup multi_scatter; do
        graph=graphs/splat.json
        [ $mode = multi_scatter ] && graph=graphs/splat_motion_blur.json
        echo "== $mode, $scene, ${STAGE}x${STAGE} (GPU ms averaged over frames 2-5)"
        "$LOOM" render $graph --scene "$scene" --width "$STAGE" --height "$STAGE" --frames "${STAGE_FRAMES:-5}" \
            --set temporal.mode=$mode --timings --quiet --out "$OUT/stages_$mode.png" | sed "/^resource/,\$d"
    done
done
uptime
