#!/usr/bin/env bash
# Installs what is missing, builds, and runs knitsim's main job on a built-in default:
# a 12×12 stockinette swatch is built from its knit pattern, relaxed toward rest, and
# rendered to a PNG. Usage: scripts/demo.sh [output directory, default out/demo]
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
if [ -d "$out" ] && [ -n "$(ls -A "$out")" ] && [ ! -f "$out/summary.json" ] &&
  [ ! -f "$out/log.csv" ]; then
  echo "demo: $out already holds files that are not a knitsim run; choose another directory" >&2
  exit 1
fi
scripts/setup.sh
./build/knitsim relax stockinette --rows 12 --cols 12 --max-time 0.5 --overwrite --out "$out"
./build/knitsim render "$out/relaxed.kstate" --color-rows --size 1024x768 --out "$out/relaxed.png"
echo "demo: the relaxed swatch is pictured in $out/relaxed.png (states, log.csv and summary.json beside it)"
