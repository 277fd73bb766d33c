#!/usr/bin/env bash
# PT (graphs/pt.json) vs ReSTIR PT (graphs/restir_pt.json) at equal GPU time against a 9-bounce
# path-traced reference: static camera (accumulated, converging), still and moving camera (the
# last single frame of a 16-frame sequence at equal time per frame, REPEATS seeds), on
# scenes/glossy_spheres.json and (when ../shared/scenes is there) veach-ajar; then the GPU ms of
# each ReSTIR PT stage at 256x256.
# Prints tables; never asserts. Run from anywhere; BUILD defaults to build-bench.
#
#   bash bench/restir_equal_time.sh                 # 128x128, 6 s GPU per configuration
#   WIDTH=64 HEIGHT=64 BUDGET_MS=2000 bash bench/restir_equal_time.sh   # quicker
#
# Outputs (out/restir_equal_time/): restir_equal_time.csv (relMSE/MAPE at every budget step),
# summary.csv, <scene>_static.png/.svg (relMSE vs GPU time), final images. The reference is
# cached in out/reference/<scene>_<W>x<H>_32x64spp_b9.exr. On lavapipe (2 cores) the whole run
# takes about 10 minutes, most of it veach-ajar (scene upload ~15 s per renderer) and the
# references. The compared image is accum.output: accumulated ReSTIR frames are correlated
# (they share reservoirs) but consistent. GPU timings depend on the machine's load: run it on
# an idle machine and report `uptime`.
source "$(dirname "$0")/lib.sh"
uptime
"$LOOM" run scripts/restir_equal_time.lua width="${WIDTH:-128}" height="${HEIGHT:-128}" \
    budget_ms="${BUDGET_MS:-6000}" steps=5 move_frames=16 repeats="${REPEATS:-8}" ref_frames=32 ref_spp=64 \
    out=out/restir_equal_time
for scene in scenes/glossy_spheres.json ../shared/scenes/veach-ajar/scene.xml; do
    [ -e "$scene" ] || continue
    echo "== ReSTIR PT stages, $scene, 256x256 (GPU ms averaged over frames 2-5)"
    "$LOOM" render graphs/restir_pt.json --scene "$scene" --width 256 --height 256 --frames 5 \
        --timings --out out/restir_equal_time/stages_"$(basename "$(dirname "$scene")")".png
done
uptime
