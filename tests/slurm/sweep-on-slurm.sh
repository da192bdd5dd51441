#!/usr/bin/env bash
# A sweep run for real through SLURM on a single-node cluster on this
# machine (started by start-local-slurm.sh): `irtp sweep slurm --submit`
# (an array of bundled shards, throttled, and a merge job after it), wait,
# then compare the merged results.csv with a local `irtp sweep run` of the
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
plan=tests/slurm/plan.toml
"$bin" sweep run "$plan" --out "$work/local" >/dev/null
# 13 points, 3 per task: 5 array tasks, at most 2 at a time.
"$bin" sweep slurm "$plan" --out "$work/cluster" --points-per-task 3 --max-array 10 \
  --throttle 2 --cpus-per-task 1 --time 00:10:00 --submit | tee "$work/submit.txt"
array=$(sed -n 's/.*array job \([0-9]*\),.*/\1/p' "$work/submit.txt")
merge=$(sed -n 's/.*merge job \([0-9]*\).*/\1/p' "$work/submit.txt")
[ -n "$array" ] && [ -n "$merge" ] || { echo "sweep-on-slurm: no job ids in the output" >&2; exit 1; }
for _ in $(seq 1 300); do
  if [ -z "$(squeue -h -j "$array,$merge" 2>/dev/null)" ]; then break; fi
  sleep 1
done
if [ -n "$(squeue -h -j "$array,$merge" 2>/dev/null)" ]; then
  echo "sweep-on-slurm: jobs still queued after 300 s" >&2; squeue >&2; exit 1
fi
cat "$work"/cluster/slurm/merge-*.out
"$bin" sweep status "$work/cluster"
python3 - "$work/local/results.csv" "$work/cluster/results.csv" <<'PY'
import csv, sys
def table(path):
    rows = list(csv.reader(open(path)))
    wall = rows[0].index("wall_time_s")
    return [[c for i, c in enumerate(r) if i != wall] for r in rows]
a, b = table(sys.argv[1]), table(sys.argv[2])
assert len(a) == 14, f"{len(a) - 1} points"
assert all(r[a[0].index("status")] == "ok" for r in a[1:])
assert a == b, "the SLURM sweep differs from the local run"
print(f"sweep-on-slurm: {len(a) - 1} points through SLURM equal the local run bit for bit")
PY
ntasks=$(ls "$work"/cluster/slurm/task-*.out | wc -l)
[ "$ntasks" -eq 5 ] || { echo "sweep-on-slurm: expected 5 array tasks, saw $ntasks" >&2; exit 1; }
rm -rf "$work"
