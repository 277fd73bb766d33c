#!/usr/bin/env bash
# README command (1): install packages, configure, build, render a first image on the default
# device (lavapipe, so no GPU is needed) and print where the image went.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build
# The Cornell box through the reference path tracer (graphs/pt.json), 64 frames of 1 spp.
./build/apps/loom render graphs/pt.json --scene scenes/cornell_box.json --width 256 --height 256 \
  --frames 64 --output accum.output=out/cornell_box.exr --output tm.output=out/cornell_box.png "$@"
echo "loom: images are in $(pwd)/out/ (cornell_box.png for viewing, cornell_box.exr linear HDR)"
