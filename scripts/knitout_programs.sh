#!/usr/bin/env bash
# The textiles-lab knitout programs (tests/data/knitout/) as `knitsim relax` reads them: for
# each, whether it is laid as yarn (and at what size) or refused (and why); each laid one
# is relaxed for MAX_TIME s of simulated time with every step checked for crossings, and
# rendered; those of at most REST_STITCHES stitches are also relaxed to rest (FIRE with
# imex-contact at 6e-4 s, as docs/relax.md relaxes quickly; its force-residual test; at
# most 5 s). Prints a Markdown table (docs/results.md, "Knitout
# programs through the knit graph"); the renders go to OUT/<program>.png.
#
#   scripts/knitout_programs.sh [OUT] [MAX_TIME] [REST_STITCHES]
#                                  (default out/knitout, 0.05 s, 0: none to rest)
#
# Takes about 9 minutes on 2 cores (the three 80 × 123 basic-vol sheets are most of it),
# about 25 with REST_STITCHES 1300 (five FIRE runs of 5 s).
# Needs build/knitsim.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/knitout}
max_time=${2:-0.05}
rest_stitches=${3:-0}
knitsim=build/knitsim
mkdir -p "$out"
echo "| program | loops in its graph | read as | relaxed $max_time s: course × wale (cm) | wall (s) | steps checked | crossings | to rest (FIRE): simulated s, wall s, course × wale (cm) |"
echo "|---|---|---|---|---|---|---|---|"
for prog in tests/data/knitout/*.k tests/data/knitout/*.knitout; do
  name=$(basename "$prog")
  loops=$("$knitsim" graph "$prog" | /usr/bin/python3 -c 'import json,sys; print(json.load(sys.stdin)["loops"]["total"])')
  run="$out/runs/$name"
  if err=$("$knitsim" relax "$prog" --max-time "$max_time" --no-frames --quiet --check-crossings \
             --overwrite --out "$run" 2>&1 >/dev/null); then
    "$knitsim" render "$run/relaxed.kstate" --size 480x360 --out "$out/${name%.*}.png" >/dev/null
    rest="$out/rest/$name"
    stitches=$(/usr/bin/python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print(s["rows"]*s["cols"])' "$run/summary.json")
    if [ "$stitches" -le "$rest_stitches" ]; then
      "$knitsim" relax "$prog" --fire --integrator imex-contact --time-step 6e-4 --max-time 5 \
        --no-frames --quiet --check-crossings \
        --overwrite --out "$rest" >/dev/null 2>&1 || true
    fi
    /usr/bin/python3 - "$run/summary.json" "$name" "$loops" "$rest/summary.json" <<'EOF'
import json, os, sys
s = json.load(open(sys.argv[1]))
c = s["crossings"]
shape = f'{s["rows"]} rows × {s["cols"]} columns' + (" in the round" if s["in_the_round"] else "")
rest = ""
if os.path.exists(sys.argv[4]):
    r = json.load(open(sys.argv[4]))
    rest = (f'{"" if r["relaxed"] else "not at rest after "}{r["sim_time_s"]:.2f}, {r["wall_time_s"]:.0f}, '
            f'{r["course_extent_cm"]:.1f} × {r["wale_extent_cm"]:.1f}; {r["crossings"]["count"]} crossings')
print(f'| {sys.argv[2]} | {sys.argv[3]} | {shape} | {s["course_extent_cm"]:.1f} × {s["wale_extent_cm"]:.1f} '
      f'| {s["wall_time_s"]:.0f} | {c["steps_checked"]} | {c["count"]} | {rest} |')
EOF
  else
    # the reason, without the path and line (SOURCE:LINE: 'INSTRUCTION': reason)
    line=$(printf '%s\n' "$err" | grep -m1 'error:' | sed -E "s/^knitsim: error: [^:]*:([0-9]+): '([^']*)': /line \1 (\2): /; s/: [^:]*need[s]? the knit graph's own layout.*//")
    echo "| $name | $loops | refused: $line | | | | | |"
  fi
done
