#!/usr/bin/env bash
# The long relaxations that quick ones are compared against (docs/results-relaxation.md: "Against long
# damped relaxations"). For each pattern, the default damped relaxation of a
# ROWS×COLS sample (damped dynamics, imex-contact at 6e-4 s with contact reuse 0.05) runs
# REF_TIME simulated seconds from the generated yarn into OUT/PATTERN; it creeps and never
# comes to rest by the force residual, so FIRE then finishes it to R < 1 cm/s² into
# OUT/rest/PATTERN, the reference that `bench_relax_to_rest --reference OUT/rest` compares
# with. Two patterns run at once, one thread each; at 42×32 about 45 minutes a pattern
# for the damped part and 2–4 for the finish: run it in the background, e.g.
#   nohup scripts/relax_reference.sh > out/ref.log 2>&1 &
# Resumable: a stage that finished is kept, and a damped run that was interrupted (Ctrl-C,
# SIGTERM: it writes its state) or killed outright (its checkpoint, at most 10 minutes
# old: `relax --checkpoint-every`) goes on from where it stopped, so run it again after an
# interruption.
# Usage: scripts/relax_reference.sh [PATTERN...]   (default: stockinette rib2x2 garter)
# Environment: ROWS, COLS (default 42, 32), REF_TIME (default 120), OUT (default out/ref).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x build/knitsim ] || scripts/setup.sh
ROWS=${ROWS:-42}
COLS=${COLS:-32}
REF_TIME=${REF_TIME:-120}
OUT=${OUT:-out/ref}
patterns=("$@")
[ ${#patterns[@]} -gt 0 ] || patterns=(stockinette rib2x2 garter)
mkdir -p "$OUT/rest"

# a summary's number for KEY (the first one)
number() { grep -o "\"$2\": [0-9.e+-]*" "$1/summary.json" | head -n 1 | cut -d' ' -f2; }
status() { grep -o '"status": "[a-z_]*"' "$1/summary.json" 2> /dev/null | head -n 1 | cut -d'"' -f4; }

one() {
  local p=$1 damped=$OUT/$1 rest=$OUT/rest/$1
  case "$(status "$damped")" in
    ok) ;;
    interrupted | running)
      local left
      left=$(awk -v e="$REF_TIME" -v t="$(number "$damped" sim_time_s)" 'BEGIN { printf "%.17g", e - t }')
      echo "== $p: the damped relaxation goes on from t = $(number "$damped" sim_time_s) s"
      build/knitsim relax --resume "$damped/final.kstate" --max-time "$left" --no-frames \
        --threads 1 -q --out "$damped" --overwrite ;;
    *)
      echo "== $p: the damped relaxation, $REF_TIME s from the generated yarn, into $damped"
      build/knitsim relax "$p" --rows "$ROWS" --cols "$COLS" --integrator imex-contact \
        --time-step 6e-4 --contact-reuse 0.05 --residual 1 --max-time "$REF_TIME" \
        --check-every 500 --no-frames --threads 1 -q --out "$damped" --overwrite ;;
  esac
  [ "$(status "$damped")" = ok ] || { echo "relax_reference.sh: $p: the damped run ended $(status "$damped") (see $damped/summary.json)" >&2; return 1; }
  if [ "$(status "$rest")" = ok ] && grep -q '"relaxed": true' "$rest/summary.json"; then
    echo "== $p: the reference at rest is $rest"
    return 0
  fi
  echo "== $p: FIRE finishes it to rest into $rest"
  build/knitsim relax --resume "$damped/final.kstate" --fire --contact-reuse-widen 2 \
    --check-every 100 --max-time 40 --threads 1 --no-frames -q --out "$rest" --overwrite
  grep -q '"relaxed": true' "$rest/summary.json" \
    || { echo "relax_reference.sh: $p: FIRE did not reach rest in 40 s (see $rest/summary.json)" >&2; return 1; }
}

# two at a time, one thread each (the damped step is half serial: two runs use two cores
# better than one run on both)
failed=0
for ((i = 0; i < ${#patterns[@]}; i += 2)); do
  pids=()
  for p in "${patterns[@]:i:2}"; do
    one "$p" &
    pids+=($!)
  done
  for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
done
exit $failed
