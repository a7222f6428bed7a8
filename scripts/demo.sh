#!/usr/bin/env bash
# Installs what is missing, builds, and runs knitsim's main job on a built-in default:
# a 12×12 stockinette swatch is built from its knit pattern, relaxed toward rest, and
# rendered to a PNG.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
out=${1:-out/demo}
rm -rf "$out"
./build/knitsim relax stockinette --rows 12 --cols 12 --max-time 0.5 --out "$out"
./build/knitsim render "$out/relaxed.kstate" --color-rows --size 1024x768 --out "$out/relaxed.png"
echo "demo: the relaxed swatch is pictured in $out/relaxed.png (states, log.csv and summary.json beside it)"
