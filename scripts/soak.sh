#!/usr/bin/env bash
# Soak test of interrupt and resume: runs a long scene (the overhand knot pulled tight,
# 10,000 steps) and a relaxation once straight through, then again interrupted by
# SIGINT/SIGTERM every fraction of a second and resumed with the command each interrupted
# summary gives, until it finishes. The final states must be byte-identical, the logs have
# the same rows and the summaries the same fields (but for the wall-clock figures, sums
# over the legs, and the command line), and every interrupted run must have exited with
# 130/143 and written status "interrupted".
# Usage: scripts/soak.sh [BUILD_DIR (default build)] [seconds between signals, default 0.7]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
period=${2:-0.7}
knitsim="$PWD/$build/knitsim"
[ -x "$knitsim" ] || { echo "soak: $knitsim is not built" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

soak() {  # name, then the command's arguments (without --out)
  local name=$1
  shift
  "$knitsim" "$@" --quiet --out "$work/$name-whole" >/dev/null
  local out="$work/$name-cut" interrupts=0 rc cmd
  local signals=(INT TERM)
  set +e
  "$knitsim" "$@" --quiet --out "$out" >/dev/null 2>"$work/$name-leg.err" &
  local pid=$!
  while true; do
    sleep "$period"
    local sig=${signals[$((interrupts % 2))]}
    kill -s "$sig" "$pid" 2>/dev/null
    wait "$pid"
    rc=$?
    if [ "$rc" -eq 0 ]; then break; fi
    if [ "$rc" -ne 130 ] && [ "$rc" -ne 143 ]; then
      echo "soak: $name exited with $rc after $interrupts interruptions; it said:" >&2
      sed 's/^/  /' "$work/$name-leg.err" >&2
      exit 1
    fi
    interrupts=$((interrupts + 1))
    grep -q '"status": "interrupted"' "$out/summary.json" || {
      echo "soak: $name: leg $((interrupts + 1)) exited with $rc but its summary does not say" \
        "it was interrupted (status: $(grep -o '"status": "[a-z]*"' "$out/summary.json" 2>/dev/null ||
          echo 'no summary'))" >&2
      exit 1
    }
    cmd=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["resume_command"])' "$out/summary.json")
    # the command as the summary gives it, with this build's knitsim (exec: the signal
    # must reach knitsim, not a shell that leaves it running)
    eval "exec \"$knitsim\" ${cmd#knitsim }" >/dev/null 2>"$work/$name-leg.err" &
    pid=$!
  done
  set -e
  for f in final.kstate; do
    cmp -s "$work/$name-whole/$f" "$out/$f" ||
      { echo "soak: $name: $f differs from the uninterrupted run's" >&2; exit 1; }
  done
  # the log goes on in time order across the resumes, with the uninterrupted run's rows,
  # and the summary is the uninterrupted run's
  /usr/bin/python3 - "$work/$name-whole" "$out" "$name" <<'PY'
import csv, json, sys
whole, cut, name = sys.argv[1:4]
rows = [list(csv.reader(open(f"{d}/log.csv"))) for d in (whole, cut)]
t = [float(r[0]) for r in rows[1][1:]]
bad = [i for i in range(1, len(t)) if t[i] <= t[i - 1]]
if bad:
    sys.exit(f"soak: {name}: log.csv times out of order at rows {bad[:5]}")
wall = rows[0][0].index("wall_s_per_step")
strip = lambda table: [r[:wall] + r[wall + 1:] for r in table]
if strip(rows[0]) != strip(rows[1]):
    sys.exit(f"soak: {name}: log.csv has other rows than the uninterrupted run's "
             f"({len(rows[1])} rows, {len(rows[0])} uninterrupted)")
# the wall-clock figures add up the legs; the command line is the last leg's
skip = {"wall_time_s", "wall_s_per_simulated_s", "us_per_segment_step", "stage_seconds",
        "checkpoints_written", "command_line", "resumed_from"}
a, b = (json.load(open(f"{d}/summary.json")) for d in (whole, cut))
differ = sorted(k for k in set(a) | set(b) if k not in skip and a.get(k) != b.get(k))
if differ:
    sys.exit(f"soak: {name}: the summary differs from the uninterrupted run's in {differ[:8]}")
PY
  echo "soak: $name: interrupted $interrupts times, resumed each time; final state, log and summary identical"
}

soak knot simulate examples/overhand_knot.json
soak relax relax garter --rows 6 --cols 6 --max-time 0.1 --check-every 50 --ke-threshold 1e-12
