#!/usr/bin/env bash
# Installs what is missing, builds, and runs knitsim's main job on a built-in default:
# a 12×12 stockinette swatch is built from its knit pattern and relaxed toward rest
# (OUT/relax), then dropped onto a sphere standing on a floor (examples/drape_sphere.json,
# OUT/drape), and pictured: OUT/relaxed.png, OUT/drape.png and a movie of the drape in
# OUT/frames/animation.mp4. About a minute and a half on 2 cores once built.
# Usage: scripts/demo.sh [output directory, default out/demo]
# The directory is replaced only when it is empty or holds an earlier knitsim run; knitsim
# itself never empties /, the home directory or a repository's root.
set -euo pipefail
out=${1:-out/demo}
# a relative directory is the caller's, not the repository's
case $out in
  /*) ;;
  *) [ $# -eq 0 ] || out="$PWD/$out" ;;
esac
cd "$(dirname "$0")/.."
if [ -e "$out" ] && [ ! -d "$out" ]; then
  echo "demo: $out exists and is not a directory" >&2
  exit 1
fi
if [ -d "$out" ] && [ -n "$(ls -A "$out")" ] && [ ! -f "$out/relax/summary.json" ] &&
  [ ! -f "$out/drape/summary.json" ]; then
  echo "demo: $out already holds files that are not a knitsim run; choose another directory" >&2
  exit 1
fi
scripts/setup.sh
mkdir -p "$out"
# an earlier demo's files (this script's own outputs) are replaced
rm -f "$out/relaxed.png" "$out/drape.png"
./build/knitsim relax stockinette --rows 12 --cols 12 --max-time 0.4 --no-frames --overwrite -q \
  --out "$out/relax"
./build/knitsim render "$out/relax/relaxed.kstate" --color-rows --size 1024x768 --out "$out/relaxed.png"
./build/knitsim simulate examples/drape_sphere.json --knit "$out/relax/relaxed.kstate" \
  --duration 0.6 --overwrite -q --out "$out/drape"
./build/knitsim render "$out/drape/final.kstate" --view scene --color-rows --size 1024x768 \
  --out "$out/drape.png"
./build/knitsim render "$out/drape/frames" --view scene --color-rows --size 480x360 --spp 2 \
  --shadow-rays 2 --ao-rays 2 --fps 20 --overwrite --out "$out/frames"
echo "demo: the relaxed swatch is in $out/relaxed.png, the drape over the sphere in" \
  "$out/drape.png and $out/frames/animation.mp4 (states, log.csv and summary.json in" \
  "$out/relax and $out/drape)"
