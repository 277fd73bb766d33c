#!/bin/bash
# tools/new_pass.sh makes a pass, kernel, test and README in one family folder only; its C++
# and GLSL compile. (The full flow — build, `loom passes --update-docs`, run the generated
# test — is in the README's "Adding a pass"; CI does not rebuild the project for it.)
set -euo pipefail
src=$1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
mkdir -p "$work/passes" && cp -r "$src/tools" "$work/"
touch "$work/before"
bash "$work/tools/new_pass.sh" my_family MyGainFilter >/dev/null
dir=$work/passes/my_family
for f in MyGainFilterPass.cpp my_gain_filter.comp tests/test_my_gain_filter.cpp README.md; do
  [ -s "$dir/$f" ] || { echo "missing $f"; exit 1; }
done
[ "$(find "$work" -newer "$work/before" -type f | grep -v "^$dir/" | wc -l)" = 0 ] ||
  { echo "new_pass.sh wrote outside the family folder"; exit 1; }
if grep -rn "@[A-Z]*@" "$dir"; then echo "placeholders left"; exit 1; fi
grep -q "<!-- loom passes MyGainFilter -->" "$dir/README.md"
# A second pass joins the family's README; an existing pass is never overwritten.
bash "$work/tools/new_pass.sh" my_family MySecond >/dev/null
grep -q "<!-- loom passes MySecond -->" "$dir/README.md"
if bash "$work/tools/new_pass.sh" my_family MySecond 2>/dev/null; then echo "overwrote"; exit 1; fi
if bash "$work/tools/new_pass.sh" MyFamily X 2>/dev/null; then echo "bad family name accepted"; exit 1; fi
# The kernel compiles with the defines the pass's `mode` enum generates.
glslangValidator -S comp --target-env vulkan1.3 --auto-map-bindings -DMODE_SCALE=0u -DMODE_SQUARE=1u \
  -o /dev/null "$dir/my_gain_filter.comp" >/dev/null
for f in "$dir/MyGainFilterPass.cpp" "$dir/tests/test_my_gain_filter.cpp"; do
  c++ -std=c++20 -fsyntax-only -Wall -Wextra -Wno-unused-parameter -I"$src" \
    -DLOOM_SOURCE_DIR="\"$src\"" "$f"
done
echo "new_pass.sh: a family with two passes, sources compile"
