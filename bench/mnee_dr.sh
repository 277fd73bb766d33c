#!/usr/bin/env bash
# MNEE with dimension reduction (Granizo-Hidalgo & Holzschuch 2024) on the animated pool
# (scripts/mnee_dr_bench.lua): GPU ms per frame against the water's tessellation from about 100 to 2M
# triangles at 960x720 (the caustic part = the frame minus the path tracer's frame; the scene
# update's CPU ms with the triangle adjacency rebuild), then equal quality against biased SMS
# (where biased SMS's caustic RMSE reaches MNEE's, the ratio of frame times). Prints tables,
# writes CSVs under out/mnee_dr; never asserts. BUILD defaults to build-bench.
#
#   bash bench/mnee_dr.sh                                   # 960x720, n = 7 .. 1000
#   WIDTH=96 HEIGHT=72 RESOLUTIONS=7,22 FRAMES=1 EQ_FRAMES=2 REF_FRAMES=4 TRIALS=1,4 \
#     EQ_HEIGHT_SCALES=4 bash bench/mnee_dr.sh
source "$(dirname "$0")/lib.sh"
OUT=${OUT:-out}
mkdir -p "$OUT/mnee_dr"
uptime
"$LOOM" run scripts/mnee_dr_bench.lua width="${WIDTH:-960}" height="${HEIGHT:-720}" \
    resolutions="${RESOLUTIONS:-7,22,71,224,707,1000}" frames="${FRAMES:-3}" \
    eq_width="${EQ_WIDTH:-160}" eq_height="${EQ_HEIGHT:-120}" eq_frames="${EQ_FRAMES:-16}" \
    ref_frames="${REF_FRAMES:-256}" trials="${TRIALS:-1,2,4,8,16,32}" \
    eq_resolution="${EQ_RESOLUTION:-128}" eq_height_scales="${EQ_HEIGHT_SCALES:-1,4}" \
    out="$OUT/mnee_dr"
