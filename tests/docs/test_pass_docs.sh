#!/bin/bash
# The pass READMEs' tables are generated from reflect(): they must match, and a drifted table
# must be detected (a check that cannot fail is no check).
set -euo pipefail
loom=$1; shift
"$loom" passes --check-docs "$@"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
readme=$(grep -l "<!-- loom passes PathTracer -->" "$@" | head -1)
sed 's/| `maxBounces` | int \[0, 64\] | 9 |/| `maxBounces` | int [0, 64] | 8 |/' "$readme" > "$work/README.md"
cmp -s "$readme" "$work/README.md" && { echo "test edit did not apply"; exit 1; }
if "$loom" passes --check-docs "$work/README.md" 2>"$work/err"; then
  echo "a drifted table passed the check"; exit 1
fi
grep -q "PathTracer tables differ" "$work/err" || { cat "$work/err"; exit 1; }
"$loom" passes --update-docs "$work/README.md" >/dev/null
cmp "$readme" "$work/README.md"
echo "pass tables match reflect(); drift is detected and repaired"
