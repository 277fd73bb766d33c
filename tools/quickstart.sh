#!/usr/bin/env bash
# README command (1): install packages, configure, build, render a first image on the default
# device (lavapipe, so no GPU is needed), then say where the image went, how long each step
# took and what to try next.
set -euo pipefail
cd "$(dirname "$0")/.."
t0=$SECONDS
bash tools/install-deps.sh
t1=$SECONDS
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build
t2=$SECONDS
# The Cornell box through the reference path tracer (graphs/pt.json), 64 frames of 1 spp.
./build/apps/loom render graphs/pt.json --scene scenes/cornell_box.json --width 256 --height 256 \
  --frames 64 --output accum.output=out/cornell_box.exr --output tm.output=out/cornell_box.png "$@"
t3=$SECONDS
cat <<MSG

loom: packages $((t1 - t0)) s, build $((t2 - t1)) s, render $((t3 - t2)) s (lavapipe, 256x256, 64 frames)
loom: images are in $(pwd)/out/
        cornell_box.png   tone-mapped, for viewing
        cornell_box.exr   linear HDR radiance
loom: next, try
  1. the inspector (live graph, parameters, any pass's output; needs a display or xvfb-run -a):
       ./build/apps/inspector/loom-inspector graphs/restir_pt.json --scene scenes/cornell_box.json
  2. a Lua script (equal-time comparison of path tracer settings, CSV + plot in out/):
       ./build/apps/loom run scripts/equal_time.lua
  3. a Mitsuba scene:
       ./build/apps/loom render graphs/pt.json --scene ../shared/scenes/veach-ajar/scene.xml --frames 16 --out out/veach.png
     (or any Mitsuba 0.5-3 XML, glTF or OBJ file of yours)
  Every test: ctest --test-dir build -j2 (README command 2). Install: cmake --install build --prefix ~/.local
MSG
