#!/bin/bash
# usage: tools/new_pass.sh FAMILY PassName [--root DIR]
#
# Makes a working pass with a test from tools/templates/family: passes/FAMILY/PassNamePass.cpp,
# its kernel passes/FAMILY/pass_name.comp, passes/FAMILY/tests/test_pass_name.cpp and, for a
# new family, passes/FAMILY/README.md (an existing family's README gets a section). Nothing
# outside passes/FAMILY changes: the build globs pass sources and tests from family folders.
# Then: cmake --build build && ./build/apps/loom passes --update-docs passes/FAMILY/README.md
#       && ./build/tests/loom_tests_gpu --gtest_filter='PassName.*'
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --root) root=$2; shift 2 ;;
    -h|--help) sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) args+=("$1"); shift ;;
  esac
done
[ ${#args[@]} -eq 2 ] || { echo "usage: tools/new_pass.sh FAMILY PassName [--root DIR]" >&2; exit 2; }
family=${args[0]} pass=${args[1]}
[[ $family =~ ^[a-z][a-z0-9_]*$ ]] || { echo "new_pass: family '$family' must be snake_case (e.g. restir_pt)" >&2; exit 2; }
[[ $pass =~ ^[A-Z][A-Za-z0-9]*$ ]] || { echo "new_pass: pass '$pass' must be PascalCase (e.g. ReSTIRPTShade)" >&2; exit 2; }
kernel=$(echo "$pass" | sed -E 's/([a-z0-9])([A-Z])/\1_\2/g; s/([A-Z])([A-Z][a-z])/\1_\2/g' | tr 'A-Z' 'a-z')
dir=$root/passes/$family
template=$here/templates/family
for f in "$dir/${pass}Pass.cpp" "$dir/$kernel.comp" "$dir/tests/test_$kernel.cpp"; do
  [ -e "$f" ] && { echo "new_pass: $f exists; not overwriting" >&2; exit 2; }
done
fill() { sed "s/@FAMILY@/$family/g; s/@PASS@/$pass/g; s/@KERNEL@/$kernel/g" "$1" > "$2"; }
mkdir -p "$dir/tests"
fill "$template/@PASS@Pass.cpp" "$dir/${pass}Pass.cpp"
fill "$template/@KERNEL@.comp" "$dir/$kernel.comp"
fill "$template/tests/test_@KERNEL@.cpp" "$dir/tests/test_$kernel.cpp"
if [ -e "$dir/README.md" ]; then
  printf '\n## %s\n\n<!-- loom passes %s -->\n<!-- /loom passes -->\n' "$pass" "$pass" >> "$dir/README.md"
else
  fill "$template/README.md" "$dir/README.md"
fi
echo "new_pass: passes/$family/{${pass}Pass.cpp, $kernel.comp, tests/test_$kernel.cpp, README.md}"
echo "next: cmake --build build && ./build/apps/loom passes --update-docs passes/$family/README.md"
echo "      ./build/tests/loom_tests_gpu --gtest_filter='$pass.*'"
