#!/usr/bin/env bash
# Sample-space-partitioned SMS (Hong et al. 2025) at equal GPU time against a path-traced
# reference, in the caustic region (scripts/sms_equal_time.lua): PT, unbiased SMS, psms, psms +
# temporal reuse and psms + ReSTIR (bench/data/psms_configs.json); then the paper's Fig. 5
# convergence, N = 4, 8, 16, 32 with and without the prior (bench/data/psms_fig5_configs.json);
# then the caustic alone (bench/data/psms_caustic_configs.json: each graph's accumCaustic against
# unbiased SMS's caustic over CAUSTIC_REF_FRAMES frames, 512), without the path part they share.
# The first comparison also measures one frame's own image after PER_FRAME (8) frames, the error
# a real-time estimator with reuse delivers per frame. Prints tables and writes convergence plots
# under out/; never asserts. BUILD defaults to
# build-bench.
#
#   bash bench/psms_equal_time.sh                              # 64x64, 4 s of GPU time each
#   WIDTH=32 HEIGHT=32 BUDGET_MS=500 STEPS=2 bash bench/psms_equal_time.sh
source "$(dirname "$0")/lib.sh"
W=${WIDTH:-64} H=${HEIGHT:-64} BUDGET=${BUDGET_MS:-4000} STEPS=${STEPS:-3} OUT=${OUT:-out}
SCENES=${SCENES:-scenes/curved_mirror.json,scenes/wavy_slab.json}
uptime
common=(width="$W" height="$H" budget_ms="$BUDGET" steps="$STEPS" scenes="$SCENES"
        ref_frames="${REF_FRAMES:-64}" ref_spp="${REF_SPP:-64}")
echo "== equal time: SMS, psms, psms + temporal, psms + ReSTIR"
"$LOOM" run scripts/sms_equal_time.lua "${common[@]}" configs=bench/data/psms_configs.json \
    per_frame="${PER_FRAME:-8}" per_frame_sequences="${PER_FRAME_SEQUENCES:-4}" \
    out="$OUT/psms_equal_time"
echo "== the caustic alone: SMS, psms, psms + temporal, psms + ReSTIR against SMS's caustic"
"$LOOM" run scripts/sms_equal_time.lua "${common[@]}" configs=bench/data/psms_caustic_configs.json \
    caustic_ref_frames="${CAUSTIC_REF_FRAMES:-512}" per_frame="${PER_FRAME:-8}" \
    per_frame_sequences="${PER_FRAME_SEQUENCES:-4}" out="$OUT/psms_caustic_equal_time"
echo "== Fig. 5: tiles N and the prior"
"$LOOM" run scripts/sms_equal_time.lua "${common[@]}" configs=bench/data/psms_fig5_configs.json \
    out="$OUT/psms_fig5"
