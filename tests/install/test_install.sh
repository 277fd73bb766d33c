#!/usr/bin/env bash
# An installed loom (cmake --install) renders from another directory with its own copy of the
# shaders, graphs and scenes: it must not need, or silently use, the source tree.
#   test_install.sh BUILD_DIR
set -euo pipefail
build=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
for f in bin/loom share/loom/shaders/lib/integrator/nee.glsl share/loom/graphs/pt.json \
         share/loom/scripts/util.lua share/loom/scenes/cornell_box.json; do
  [ -e "$prefix/$f" ] || { echo "not installed: $f"; exit 1; }
done
mkdir "$work/run" && cd "$work/run"
export LOOM_CACHE_DIR="$work/cache" LOOM_LOG=warning
render() {
  "$prefix/bin/loom" render "$prefix/share/loom/graphs/pt.json" \
    --scene "$prefix/share/loom/scenes/cornell_box.json" --width 16 --height 16 --frames 2 \
    --output accum.output=out.exr --quiet
}
render
[ -s out.exr ] || { echo "installed loom wrote no image"; exit 1; }
# The installed copy's shaders are the ones used: break one and the render must fail.
echo "this is not GLSL" >> "$prefix/share/loom/passes/common/tonemap.comp"
if render 2>err.txt; then echo "installed loom did not use its own shaders"; exit 1; fi
grep -q "tonemap.comp" err.txt || { echo "error does not name the shader:"; cat err.txt; exit 1; }
echo "installed loom renders from $work/run with $prefix/share/loom"
