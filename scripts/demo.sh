#!/usr/bin/env bash
# Installs what is missing, builds, and runs knitsim's main job on a built-in default.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
out=${1:-out/demo}
rm -rf "$out"
./build/knitsim simulate examples/pendulum.json --out "$out"
echo "demo: states, log.csv and summary.json are in $out/"
