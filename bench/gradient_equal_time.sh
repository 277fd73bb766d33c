#!/usr/bin/env bash
# Gradient-domain ReSTIR PT (Wang et al. 2025, Fig. 8 and 12) at equal time under a moving camera
# against a high-spp path-traced reference: ReSTIR G-PT (graphs/grestir_pt.json; also without
# positivization and without adaptive spatial reuse), Area ReSTIR, gradient after ReSTIR and
# G-PT at the spp that fits the frame time, each with L2 and, in a second table, L1
# reconstruction (the solve counted in the frame time), and PT. The last single frame of a
# MOVE_FRAMES-frame swing, relMSE, MAPE and FLIP averaged over REPEATS seeds, ms per frame and
# relMSE scaled to equal time. Scenes: the Cornell box, the glossy scene and, when
# ../shared/scenes is there, staircase2-modern-hall. Then the GPU ms of every stage at 64x64.
# Prints tables; never asserts. BUILD defaults to build-bench.
#
#   bash bench/gradient_equal_time.sh                        # 64x64, 4 repeats
#   WIDTH=32 HEIGHT=32 REPEATS=2 bash bench/gradient_equal_time.sh   # quicker
# OUT (default out/gradient_equal_time) takes the tables' CSVs and images; SCENES replaces the
# project scenes, STAIRS=none skips the staircase.
source "$(dirname "$0")/lib.sh"
uptime
OUT="${OUT:-out/gradient_equal_time}"
run() {  # scene, degrees, configs, out name
    "$LOOM" run scripts/restir_equal_time.lua configs="$3" scenes="$1" cameras=moving \
        move_degrees="$2" move_frames="${MOVE_FRAMES:-8}" width="${WIDTH:-64}" height="${HEIGHT:-64}" \
        budget_ms=1 steps=1 repeats="${REPEATS:-4}" ref_frames="${REF_FRAMES:-32}" ref_spp=64 out="$OUT/$4"
}
scenes="${SCENES:-scenes/cornell_box.json scenes/glossy_spheres.json}"
stairs=${STAIRS:-../shared/scenes/staircase2-modern-hall/scene.xml}  # STAIRS=none: skip
[ -e "$stairs" ] && scenes="$scenes $stairs"
for scene in $scenes; do
    # The staircase's look-at point is 13 units away: 2 degrees move the camera 0.45.
    degrees=8
    [ "$scene" = "$stairs" ] && degrees=2
    name=$(basename "$scene" .json)
    [ "$name" = scene.xml ] && name=$(basename "$(dirname "$scene")")
    run "$scene" $degrees bench/data/gradient_configs.json "${name}_l2"
    run "$scene" $degrees bench/data/gradient_l1_configs.json "${name}_l1"
done
for scene in $scenes; do
    echo "== ReSTIR G-PT stages, $scene, ${STAGE:-64}x${STAGE:-64} (GPU ms averaged over frames 2-5)"
    "$LOOM" render graphs/grestir_pt.json --scene "$scene" --width "${STAGE:-64}" --height "${STAGE:-64}" \
        --frames 5 --timings --quiet --out "$OUT/stages.png" | sed "/^resource/,\$d"
done
uptime
