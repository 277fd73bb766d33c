#!/usr/bin/env bash
# Screened Poisson reconstruction (PoissonReconstruct): GPU ms, solver steps and the relative
# residual reached, for the papers' presets (L2 = 50 CG steps, L1 = 20 x 50) and for solving L2
# to a relative residual of 1e-4 by CG and by multigrid-preconditioned CG, on real
# inputs: graphs/poisson_pt.json (the path tracer's 1 spp frame as the primal, the gradients of
# the running mean; the Cornell box). Prints a table; never asserts. BUILD defaults to
# build-bench.
#
# "to 1e-4" runs twice: with tolerance = 1e-4 and 1000 steps allowed, which finds the steps
# needed (the steps after convergence dispatch zero groups, but on lavapipe every dispatch and
# barrier still costs ~0.4 ms), then with exactly that many steps, which is the time reported.
# "setup" is the solve with 1 step minus one step: weights, right-hand side, initial residual,
# output, common to every solver.
#
#   bash bench/poisson_solver.sh                         # 256x256, then 1920x1080 (L2 only)
#   SIZES="128x128" FRAMES=3 bash bench/poisson_solver.sh
source "$(dirname "$0")/lib.sh"
SIZES=${SIZES:-"256x256 1920x1080"} FRAMES=${FRAMES:-4}
OUT=${OUT:-out/poisson_solver}
mkdir -p "$OUT"
uptime
# name | parameters
configs=(
  "l2 cg 1 step (setup + 1)|solver=l2 linearSolver=cg iterations=1"
  "l2 cg 50 (paper)|solver=l2 linearSolver=cg iterations=50"
  "l2 cg to 1e-4|solver=l2 linearSolver=cg iterations=1000 tolerance=1e-4"
  "l2 multigrid to 1e-4|solver=l2 linearSolver=multigrid iterations=1000 tolerance=1e-4"
  "l2 jacobi 50|solver=l2 linearSolver=jacobi iterations=50"
  "l1 cg 20x50 (paper)|solver=l1 linearSolver=cg iterations=50 irlsIterations=20"
  "l1 multigrid 20x10|solver=l1 linearSolver=multigrid iterations=10 irlsIterations=20"
)
for size in $SIZES; do
  w=${size%x*} h=${size#*x}
  printf "\n%dx%d, %d frames (mean of frames 2..%d)\n" "$w" "$h" "$FRAMES" "$FRAMES"
  printf "%-24s %10s %8s %12s %12s %16s\n" config "GPU ms" steps "rel. resid." "ms/step" "ms with tol."
  for c in "${configs[@]}"; do
    name=${c%%|*} params=${c#*|}
    # L1 at 1080p takes minutes per frame on lavapipe: only where asked (L1_1080=1).
    if [[ $name == l1* && $w -gt 512 && -z ${L1_1080:-} ]]; then continue; fi
    sets=()
    for p in $params; do sets+=(--set "poisson.$p"); done
    log=$OUT/$(echo "$name-$size" | tr -c 'a-z0-9\n-' _).log
    tolms=""
    if [[ $params == *tolerance* ]]; then
      if ! "$LOOM" render graphs/poisson_pt.json --scene scenes/cornell_box.json --width "$w" \
          --height "$h" --frames "$FRAMES" "${sets[@]}" --timings > "$log.tol" 2>&1; then
        printf "%-24s failed: %s\n" "$name" "$(grep -m1 -i error "$log.tol")"
        continue
      fi
      tolms=$(grep '^poisson ' "$log.tol" | awk '{print $2}')
      need=$(grep 'poisson.iterations' "$log.tol" | awk '{print $3}')
      sets+=(--set poisson.iterations="$need" --set poisson.tolerance=0)
    fi
    if ! "$LOOM" render graphs/poisson_pt.json --scene scenes/cornell_box.json --width "$w" \
        --height "$h" --frames "$FRAMES" "${sets[@]}" --timings > "$log" 2>&1; then
      printf "%-24s failed: %s\n" "$name" "$(grep -m1 -i error "$log")"
      continue
    fi
    ms=$(grep '^poisson ' "$log" | awk '{print $2}')
    steps=$(grep 'poisson.iterations' "$log" | awk '{print $3}')
    rel=$(grep 'poisson.relativeResidual' "$log" | awk '{printf "%.3g", $3}')
    printf "%-24s %10.1f %8s %12s %12.2f %16s\n" "$name" "$ms" "$steps" "$rel" "$(echo "$ms / $steps" | bc -l)" "$tolms"
  done
done
