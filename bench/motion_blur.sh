#!/usr/bin/env bash
# What motion blur of moving shapes costs (scripts/motion_blur_cost.lua): GPU ms per frame and
# the scene update's CPU ms (of which the BVH build) with the shutter closed and open, for the
# path tracer and multi-splatting, on scenes with moving shapes (fine_geometry's rolling sphere).
# Prints a table; never asserts. BUILD defaults to build-bench.
#
#   bash bench/motion_blur.sh                          # 256x256, 4 frames
#   WIDTH=32 HEIGHT=32 FRAMES=1 bash bench/motion_blur.sh
source "$(dirname "$0")/lib.sh"
uptime
"$LOOM" run scripts/motion_blur_cost.lua width="${WIDTH:-256}" height="${HEIGHT:-256}" \
    frames="${FRAMES:-4}" shutter="${SHUTTER:-1}" scenes="${SCENES:-scenes/fine_geometry.json}"
uptime
