#!/usr/bin/env bash
# loom sweep-submit on a real single-node Slurm (tools/slurm-local.sh): a 4-task sweep of a
# tiny ablation merges to exactly the unsharded run; a failed task is named by the merge job,
# which merges nothing; --retry resubmits only that task and the sweep then completes.
# Skips (exit 77) where Slurm cannot start: not root, or slurm-wlm/munge not installed.
set -uo pipefail
loom=$(realpath "$1")
src=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d /tmp/loom-slurm-test.XXXXXX)
export LOOM_SLURM_DIR=$work/cluster LOOM_SLURM_PORT=$((17000 + RANDOM % 2000)) LOOM_PROGRESS=0
cleanup() { bash "$src/tools/slurm-local.sh" stop >/dev/null 2>&1; rm -rf "$work"; }
trap cleanup EXIT
start_out=$(timeout 120 bash "$src/tools/slurm-local.sh" start 2>&1)
rc=$?
if [ $rc -eq 77 ]; then echo "SKIP: $start_out"; exit 77; fi
[ $rc -eq 0 ] || { echo "FAIL: the cluster did not start (exit $rc):"; echo "$start_out"; exit 1; }
echo "$start_out"
export SLURM_CONF=$LOOM_SLURM_DIR/slurm.conf
fail() { echo "FAIL: $*"; for f in "$work"/sweep*/logs/*.out; do [ -f "$f" ] && { echo "--- $f"; tail -n 20 "$f"; }; done; exit 1; }

# Waits until DIR/DONE exists or the merge job has ended (it failed), at most $2 seconds.
wait_sweep() {
  local dir=$1 limit=$2 merge
  merge=$(awk '/^merge/ {id=$2} END {print id}' "$dir/jobs.txt")
  for _ in $(seq $((limit * 2))); do
    [ -f "$dir/DONE" ] && return 0
    if ! timeout 10 squeue -h -j "$merge" 2>/dev/null | grep -q .; then
      sleep 1
      [ -f "$dir/DONE" ] && return 0
      return 1
    fi
    sleep 0.5
  done
  fail "sweep in $dir did not finish within $limit s"
}

cd "$work" || exit 1
args=(width=16 height=16 frames=2 values=1,2,3,5,9 ref_frames=2 ref_spp=4 reference=ref.exr)

# 1. The unsharded run, then the same sweep as a 4-task array job with its merge job.
"$loom" run --quiet "$src/scripts/ablation.lua" "${args[@]}" out=plain >/dev/null ||
  fail "unsharded ablation run"
"$loom" sweep-submit "$src/scripts/ablation.lua" --tasks 4 --dir sweep1 "${args[@]}" out=slurm \
  >submit.txt || fail "sweep-submit: $(cat submit.txt)"
grep -q "array job" submit.txt && grep -q "merge job" submit.txt || fail "no job ids: $(cat submit.txt)"
wait_sweep sweep1 300 || fail "the sweep's merge job failed"
cmp -s plain/ablation.csv slurm/ablation.csv ||
  fail "merged CSV differs from the unsharded run: $(diff plain/ablation.csv slurm/ablation.csv)"
[ "$(wc -l <slurm/ablation.csv)" -eq 6 ] || fail "expected 5 rows and a header"
[ -f slurm/ablation.png ] || fail "the merge job's plot step wrote no slurm/ablation.png"
for i in 0 1 2 3; do
  [ "$(cat sweep1/status/task-$i.rc)" = 0 ] || fail "task $i status"
  head -1 "slurm/ablation.PART-$i.csv" | grep -q "^# loom-sweep id=.* shard=$i/4$" ||
    fail "part $i has no sweep line"
done
echo "ok: 4-task sweep merged equals the unsharded run"

# 2. A failing task: the merge job names it and merges nothing; a retry of that task alone
#    completes the sweep.
touch fail.mark
"$loom" sweep-submit "$src/tests/slurm/flaky_sweep.lua" --tasks 4 --dir sweep2 fail_file=fail.mark \
  out=flaky >/dev/null || fail "sweep-submit (flaky)"
wait_sweep sweep2 120 && fail "the merge job succeeded although task 2 failed"
grep -q "task 2: exit code 2" sweep2/logs/merge.out || fail "merge job did not name task 2: $(cat sweep2/logs/merge.out)"
grep -q "nothing merged" sweep2/logs/merge.out || fail "merge job output"
[ ! -e flaky/flaky.csv ] || fail "a partial merged file was written"
rm fail.mark
"$loom" sweep-submit --retry sweep2 >retry.txt || fail "retry: $(cat retry.txt)"
grep -q "tasks 2 of 4" retry.txt || fail "retry did not resubmit task 2 only: $(cat retry.txt)"
wait_sweep sweep2 120 || fail "the retried sweep's merge job failed"
printf 'index,square,value\n1,1,1\n2,4,2\n3,9,3\n4,16,4\n' >expected.csv
cmp -s expected.csv flaky/flaky.csv || fail "retried sweep: $(cat flaky/flaky.csv)"
echo "ok: failed task named, nothing merged; --retry resubmitted task 2 and completed the sweep"

# 3. Parts of different sweeps never merge.
"$loom" run --quiet "$src/tests/slurm/flaky_sweep.lua" --shard 0/2 out=mix >/dev/null
"$loom" run --quiet "$src/tests/slurm/flaky_sweep.lua" --shard 1/2 out=mix other=1 >/dev/null
"$loom" merge mix/flaky.csv mix/flaky.PART-0.csv mix/flaky.PART-1.csv >merge.txt 2>&1
rc=$?
[ $rc -eq 2 ] && grep -q "parts of different sweeps do not merge" merge.txt ||
  fail "merge of different sweeps: exit $rc: $(cat merge.txt)"
echo "ok: parts of different sweeps refused"
