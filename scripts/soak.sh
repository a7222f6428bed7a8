#!/usr/bin/env bash
# Soak test of interrupt and resume: runs a long scene (the overhand knot pulled tight,
# 10,000 steps) and a relaxation once straight through, then again interrupted by
# SIGINT/SIGTERM every fraction of a second and resumed with the command each interrupted
# summary gives, until it finishes. The final states must be byte-identical and every
# interrupted run must have exited with 130/143 and written status "interrupted".
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
  "$knitsim" "$@" --quiet --out "$out" >/dev/null 2>&1 &
  local pid=$!
  while true; do
    sleep "$period"
    local sig=${signals[$((interrupts % 2))]}
    kill -s "$sig" "$pid" 2>/dev/null
    wait "$pid"
    rc=$?
    if [ "$rc" -eq 0 ]; then break; fi
    if [ "$rc" -ne 130 ] && [ "$rc" -ne 143 ]; then
      echo "soak: $name exited with $rc after $interrupts interruptions" >&2
      exit 1
    fi
    interrupts=$((interrupts + 1))
    grep -q '"status": "interrupted"' "$out/summary.json" ||
      { echo "soak: $name: an interrupted run's summary does not say so" >&2; exit 1; }
    cmd=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["resume_command"])' "$out/summary.json")
    # the command as the summary gives it, with this build's knitsim
    eval "\"$knitsim\" ${cmd#knitsim }" >/dev/null 2>&1 &
    pid=$!
  done
  set -e
  for f in final.kstate; do
    cmp -s "$work/$name-whole/$f" "$out/$f" ||
      { echo "soak: $name: $f differs from the uninterrupted run's" >&2; exit 1; }
  done
  # the log goes on in time order across the resumes
  /usr/bin/python3 - "$out/log.csv" <<'PY'
import sys
t = [float(l.split(",")[0]) for l in open(sys.argv[1]).read().split("\n")[1:] if l]
bad = [i for i in range(1, len(t)) if t[i] <= t[i - 1]]
if bad:
    sys.exit(f"soak: log.csv times out of order at rows {bad[:5]}")
PY
  echo "soak: $name: interrupted $interrupts times, resumed each time; final state identical"
}

soak knot simulate examples/overhand_knot.json
soak relax relax garter --rows 6 --cols 6 --max-time 0.1 --check-every 50 --ke-threshold 1e-12
