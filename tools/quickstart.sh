#!/usr/bin/env bash
# README command (1): install packages, configure, build, render a first image on the default
# device (lavapipe, so no GPU is needed) and print where the image went.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build
GRAPH=${1:-graphs/hello_compute.json}
shift || true
./build/apps/loom render "$GRAPH" --width 320 --height 240 --frames 64 --out out/first.exr \
  --output tm.output=out/first.png "$@"
echo "loom: images are in $(pwd)/out/ (first.png for viewing, first.exr linear HDR)"
