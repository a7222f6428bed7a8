#!/usr/bin/env bash
# Builds and runs knitsim's benchmarks: scripts/bench.sh
#   [step|relax|scaling|threads|contact|step_limit|time_to_solution]... (none: the first
# five). Each prints one JSON document; they are also saved under out/bench/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
mkdir -p out/bench
which=("$@")
[ ${#which[@]} -gt 0 ] || which=(step threads scaling relax contact)
for b in "${which[@]}"; do
  case "$b" in
    step|relax|scaling|threads|step_limit|time_to_solution) args=() ;;
    contact) args=(11264 20 2 5) ;;
    *) echo "bench.sh: unknown benchmark '$b' (step, relax, scaling, threads, contact, step_limit, time_to_solution)" >&2; exit 1 ;;
  esac
  echo "== $b" >&2
  ./build/bench_$b "${args[@]}" | tee "out/bench/$b.json"
done
