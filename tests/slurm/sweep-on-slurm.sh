#!/usr/bin/env bash
# Sweeps run for real through SLURM on a single-node cluster on this
# machine (started by start-local-slurm.sh, MaxArraySize 11):
#  1. `irtp sweep slurm --submit` with bundled shards (13 points, 3 per task:
#     one array of 5 tasks, MaxArraySize read from scontrol);
#  2. a plan larger than MaxArraySize (25 points, one per task): three
#     arrays, chained, every point once;
#  3. points lost after the run: `sweep status` prints the resubmission,
#     `sweep slurm --missing --submit` runs only the tasks that hold them.
# Each merged results.csv is compared with a local `irtp sweep run` of the
# same plan, bit for bit (every column but wall_time_s).
#
# If SLURM cannot start here the test FAILS, loudly, unless
# IRTP_ALLOW_NO_SLURM=1 is set (then it says it was skipped).
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=$(realpath "${IRTP_BIN:-target/debug/irtp}")
[ -x "$bin" ] || cargo build --locked --bin irtp

if ! bash tests/slurm/start-local-slurm.sh; then
  echo "!!!!!!!! SLURM could not be started on this machine: the real-SLURM sweep test DID NOT RUN !!!!!!!!" >&2
  if [ "${IRTP_ALLOW_NO_SLURM:-0}" = 1 ]; then
    echo "sweep-on-slurm: skipped (IRTP_ALLOW_NO_SLURM=1)" >&2
    exit 0
  fi
  exit 1
fi

work=$(mktemp -d /tmp/irtp-slurm-test.XXXXXX)
fail() { echo "sweep-on-slurm: $*" >&2; exit 1; }

# Submit with the given flags into $work/$1 and wait for every job.
submit_and_wait() {
  local dir=$1; shift
  "$bin" sweep slurm "$@" --submit | tee "$work/$dir.submit.txt"
  local ids
  ids=$(sed -n 's/.*array jobs \([0-9, ]*\); merge job \([0-9]*\).*/\1,\2/p' "$work/$dir.submit.txt" | tr -d ' ')
  [ -n "$ids" ] || fail "no job ids in the output"
  for _ in $(seq 1 300); do
    [ -z "$(squeue -h -j "$ids" 2>/dev/null)" ] && break
    sleep 1
  done
  [ -z "$(squeue -h -j "$ids" 2>/dev/null)" ] || { squeue >&2; fail "jobs still queued after 300 s"; }
}

# The merged table of $2 equals the local run $1 (rows: $3 points).
same_table() {
  python3 - "$1/results.csv" "$2/results.csv" "$3" <<'PY'
import csv, sys
def table(path):
    rows = list(csv.reader(open(path)))
    wall = rows[0].index("wall_time_s")
    return [[c for i, c in enumerate(r) if i != wall] for r in rows]
a, b = table(sys.argv[1]), table(sys.argv[2])
assert len(a) == int(sys.argv[3]) + 1, f"{len(a) - 1} points"
assert all(r[a[0].index("status")] == "ok" for r in a[1:])
assert a == b, "the SLURM sweep differs from the local run"
print(f"sweep-on-slurm: {len(a) - 1} points through SLURM equal the local run bit for bit")
PY
}

# 1. Bundled: 13 points, 3 per task, one array of 5 tasks, at most 2 at a time.
plan=tests/slurm/plan.toml
"$bin" sweep run "$plan" --out "$work/local" >/dev/null
submit_and_wait cluster "$plan" --out "$work/cluster" --points-per-task 3 \
  --throttle 2 --cpus-per-task 1 --time 00:10:00
grep -q "in 1 arrays (MaxArraySize 11: scontrol show config)" "$work/cluster.submit.txt" \
  || fail "MaxArraySize not read from scontrol"
cat "$work"/cluster/slurm/merge-*.out
"$bin" sweep status "$work/cluster"
same_table "$work/local" "$work/cluster" 13
ntasks=$(ls "$work"/cluster/slurm/task-*.out | wc -l)
[ "$ntasks" -eq 5 ] || fail "expected 5 array tasks, saw $ntasks"

# 2. Split: 25 points, one per task, MaxArraySize 11: arrays of 11, 11, 3.
plan=tests/slurm/plan-split.toml
"$bin" sweep run "$plan" --out "$work/local-split" >/dev/null
submit_and_wait split "$plan" --out "$work/split" --throttle 4 --time 00:10:00
grep -q "25 of 25 array tasks of at most 1 items in 3 arrays" "$work/split.submit.txt" \
  || fail "the 25-point plan was not split into 3 arrays"
same_table "$work/local-split" "$work/split" 25
ntasks=$(ls "$work"/split/slurm/task-*.out | wc -l)
[ "$ntasks" -eq 25 ] || fail "expected 25 array tasks, saw $ntasks"

# 3. Two points lost: status says so (exit 3) and prints the resubmission,
# which runs only the two tasks that hold them.
for p in $(ls "$work/split/workspace" | grep -v '^\.' | sed -n '4p;17p'); do rm -r "$work/split/workspace/$p"; done
rc=0; "$bin" sweep status "$work/split" >"$work/status.txt" || rc=$?
cat "$work/status.txt"
[ "$rc" -eq 3 ] || fail "sweep status exit $rc with 2 points missing (expected 3)"
grep -q -- "--missing --submit" "$work/status.txt" || fail "status does not print the resubmission"
before=$(ls "$work"/split/slurm/task-*.out | wc -l)
submit_and_wait resubmit "$plan" --out "$work/split" --missing --throttle 4 --time 00:10:00
grep -q "2 of 25 array tasks" "$work/resubmit.submit.txt" || fail "the resubmission did not take exactly 2 tasks"
after=$(ls "$work"/split/slurm/task-*.out | wc -l)
[ $((after - before)) -eq 2 ] || fail "the resubmission ran $((after - before)) tasks, not 2"
"$bin" sweep status "$work/split"
same_table "$work/local-split" "$work/split" 25
rm -rf "$work"
