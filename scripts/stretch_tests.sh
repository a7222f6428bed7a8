#!/usr/bin/env bash
# The stretch tests of docs/results-stretch.md, reproducible with one command: stockinette, garter and
# 2×2 rib, each relaxed and pulled along the course, the wale and the bias with the yarn
# model; then the elastic sheet (Baraff–Witkin), fitted to the stockinette's three runs at
# small strain, pulled the same ways on each knit; one force–strain figure per direction
# with every curve, and renders of each knit beside its sheet at the same strain.
# Resumable: a relaxation or run that finished is kept, and a yarn pull stopped partway
# (interrupted, or killed with the machine) goes on from its latest sample
# (`stretch --resume DIR`), so run it again after an interruption. Long (about an hour at 12×12 on 2 cores): run it in the background, e.g.
#   nohup scripts/stretch_tests.sh > out/stretch.log 2>&1 &
# Usage: scripts/stretch_tests.sh [--rows R] [--cols C] [--speed V] [--to E] [--wale-to E]
#                                 [--threads N] [--friction MU] [--directions LIST] [--bind-off]
#                                 [--bias-bound] [--cast-on] [--sheet-directions LIST]
#                                 [--patterns LIST] [--max-force F]
# --to is the strain of the course and bias pulls (default 1), --wale-to the wale pull's
# (default 0.6: a stockinette's loops jam at about 0.8 along the wale, where the
# inextensible yarn stops the pull and the run ends unstable). A run that ends unstable
# keeps its curve up to there and is not repeated.
# --friction MU: the yarn runs with yarn–yarn Coulomb friction MU in place of the non-rigid
# damping filter (--yarn-friction MU --alpha-small 0 --alpha-large 0), whose curves do not
# depend on the pulling speed, and with the yarn ends' mass floor (--end-mass-floor 0.5:
# with nothing to damp them, a free end's light control points jitter at the step); they
# and their sheets go to out/stretch/RxC/friction_MU
# (the relaxations are shared).
# --bind-off: the samples are knitted with their last row bound off (`relax --bind-off`),
# so that the bias pull cannot ladder the top edge; relaxations and runs go to
# out/stretch/RxC_bound.
# --bias-bound: the course and wale pulls on live samples, the bias pulls on bound-off ones
# (those of --bind-off, in out/stretch/RxC_bound/…): a bias pull from a corner ladders a live
# top edge, while the course and wale clamps hold the edges that a bind-off would change.
# The sheet and the figures then take each direction's runs from where they are.
# --cast-on (with --bind-off or --bias-bound): the bound-off samples have their first row
# cast on too (`relax --cast-on`), so that a bias pull cannot draw the first row's yarn out
# at the fixed corner either; they go to out/stretch/RxC_bound_cast.
# --sheet-directions LIST: the sheet's fit and pulls in these directions only (default
# course,wale,bias; course is needed). The bias fit and pulls of the sheet are the slow
# ones: the sheet wrinkles along the bias (a 42×32 bias sheet pull takes about 10 minutes on
# 1 thread, its course pull 1). The fit is kept in the stockinette's course sheet run:
# remove the *_sheet runs after changing this.
# --patterns LIST: the knits whose yarn pulls run now, a comma-separated subset of
# stockinette,garter,rib2x2 (default all three; two instances with different patterns can
# run side by side); the sheet and the figures wait until every yarn pull has ended.
# --directions LIST: the yarn pulls to run now, a comma-separated subset of course,wale,bias
# (default all three); the sheet and the figures wait until every yarn pull has ended.
# --max-force F: every yarn pull ends (ok) at its first sample with a clamp over F dyn (a
# load limit, `stretch --max-force`), instead of running into the jam until a step fails;
# runs that already ended are kept as they are.
# KNITSIM=PATH runs another knitsim binary (e.g. a copy, so that a rebuild of build/ does
# not change a long run halfway).
set -euo pipefail
cd "$(dirname "$0")/.."
rows=12 cols=12 speed=1 to=1.0 wale_to=0.6 threads=0 friction= directions=course,wale,bias bind_off=
bias_bound= sheet_directions=course,wale,bias cast_on= patterns=stockinette,garter,rib2x2
max_force=
while [ $# -gt 0 ]; do
  case $1 in
    --rows) rows=$2; shift 2 ;;
    --cols) cols=$2; shift 2 ;;
    --speed) speed=$2; shift 2 ;;
    --to) to=$2; shift 2 ;;
    --wale-to) wale_to=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --friction) friction=$2; shift 2 ;;
    --directions) directions=$2; shift 2 ;;
    --bind-off) bind_off=--bind-off; shift ;;
    --bias-bound) bias_bound=1; shift ;;
    --cast-on) cast_on=--cast-on; shift ;;
    --patterns) patterns=$2; shift 2 ;;
    --sheet-directions) sheet_directions=$2; shift 2 ;;
    --max-force) max_force=$2; shift 2 ;;
    *) echo "stretch_tests: unknown option '$1'" >&2; exit 2 ;;
  esac
done
for d in ${directions//,/ }; do
  case $d in
    course | wale | bias) ;;
    *) echo "stretch_tests: --directions: unknown direction '$d' (course, wale, bias)" >&2; exit 2 ;;
  esac
done
for p in ${patterns//,/ }; do
  case $p in
    stockinette | garter | rib2x2) ;;
    *) echo "stretch_tests: --patterns: unknown pattern '$p' (stockinette, garter, rib2x2)" >&2; exit 2 ;;
  esac
done
k=${KNITSIM:-./build/knitsim}
[ -n "${KNITSIM:-}" ] || [ -x build/knitsim ] || scripts/setup.sh
[ -x "$k" ] || { echo "stretch_tests: KNITSIM=$k is not an executable" >&2; exit 2; }
case ",$sheet_directions," in
  *,course,*) ;;
  *) echo "stretch_tests: --sheet-directions must include course (its run does the fit)" >&2; exit 2 ;;
esac
for d in ${sheet_directions//,/ }; do
  case $d in
    course | wale | bias) ;;
    *) echo "stretch_tests: --sheet-directions: unknown direction '$d' (course, wale, bias)" >&2; exit 2 ;;
  esac
done
if [ -n "$bias_bound" ] && [ -n "$bind_off" ]; then
  echo "stretch_tests: --bias-bound binds off the bias pulls' samples only; --bind-off all of them" >&2
  exit 2
fi
if [ -n "$cast_on" ] && [ -z "$bind_off$bias_bound" ]; then
  echo "stretch_tests: --cast-on casts on the bound-off samples: give --bind-off or --bias-bound" >&2
  exit 2
fi
relaxed=out/stretch/${rows}x${cols}${bind_off:+_bound${cast_on:+_cast}}
root=$relaxed
yarn=()
if [ -n "$friction" ]; then
  root=$relaxed/friction_$friction
  yarn=(--yarn-friction "$friction" --alpha-small 0 --alpha-large 0 --end-mass-floor 0.5)
fi
[ -n "$max_force" ] && yarn+=(--max-force "$max_force")
bound=out/stretch/${rows}x${cols}_bound${cast_on:+_cast}
bound_root=$bound${friction:+/friction_$friction}
mkdir -p "$root"
# where each direction's samples and runs are: with --bias-bound the bias pulls' are bound off
bias_bound() { [ -n "$bias_bound" ] && [ "$1" = bias ]; }
relax_dir() { if bias_bound "$2"; then echo "$bound/$1_relax"; else echo "$relaxed/$1_relax"; fi; }
yarn_run() { if bias_bound "$2"; then echo "$bound_root/$1_$2"; else echo "$root/$1_$2"; fi; }
sheet_run() { if bias_bound "$2"; then echo "$root/$1_$2_bound_sheet"; else echo "$root/$1_$2_sheet"; fi; }
relaxed_knit() {
  if [ -f "$1/relaxed.kstate" ]; then echo "$1/relaxed.kstate"; else echo "$1/final.kstate"; fi
}
done_ok() { [ -f "$1/summary.json" ] && grep -q '"status": "ok"' "$1/summary.json"; }
# a run that ended (ok or unstable) and wrote its curve; an interrupted one goes again
ended() {
  [ -f "$1/stretch.csv" ] && [ -f "$1/summary.json" ] && ! grep -q '"status": "interrupted"' "$1/summary.json"
}
strain_of() { if [ "$1" = wale ]; then echo "$wale_to"; else echo "$to"; fi; }

for p in ${patterns//,/ }; do
  for d in ${directions//,/ }; do
    relax=$(relax_dir $p $d)
    if [ ! -f "$relax/final.kstate" ] || ! done_ok "$relax"; then
      mkdir -p "$(dirname "$relax")"
      off=$bind_off
      bias_bound $d && off=--bind-off
      [ -n "$off" ] && off="$off $cast_on"
      $k relax $p --rows "$rows" --cols "$cols" $off --max-time 1 -j "$threads" -q --overwrite \
        --out "$relax"
    fi
    knit=$(relaxed_knit "$relax")
    run=$(yarn_run $p $d)
    ended "$run" && continue
    mkdir -p "$(dirname "$run")"
    # a run stopped partway (interrupted, or killed with the machine) goes on where its
    # curve ends; anything else starts afresh
    again=(--overwrite)
    [ -f "$run/stretch.csv" ] && [ -d "$run/frames" ] && again=(--resume "$run")
    $k stretch --from "$knit" --direction $d --to "$(strain_of $d)" \
      --speed "$speed" "${yarn[@]}" -j "$threads" -q "${again[@]}" --out "$run" ||
      [ "${again[0]}" = --overwrite ] ||
      $k stretch --from "$knit" --direction $d --to "$(strain_of $d)" \
        --speed "$speed" "${yarn[@]}" -j "$threads" -q --overwrite --out "$run" || true
  done
done

missing=
for p in stockinette garter rib2x2; do
  for d in course wale bias; do ended "$(yarn_run $p $d)" || missing="$missing ${p}_$d"; done
done
if [ -n "$missing" ]; then
  echo "stretch_tests: yarn pulls still to run:$missing; the sheet and the figures wait for them"
  exit 0
fi

# the sheet: fitted once to the stockinette (its course run does the fit), then given
# every knit's geometry with the fitted stiffnesses
fit=
for d in ${sheet_directions//,/ }; do fit=$fit${fit:+,}$(yarn_run stockinette $d); done
first=$(sheet_run stockinette course)
ended "$first" || $k stretch --from "$(relaxed_knit "$(relax_dir stockinette course)")" --sheet \
  --fit "$fit" --direction course --to "$to" --speed "$speed" -q --overwrite --out "$first"
fitted() { grep -o "\"$1\": [0-9.e+-]*" "$first/summary.json" | head -n 1 | cut -d' ' -f2; }
material=(--k-course "$(fitted k_stretch_u_dyn_per_cm)" --k-wale "$(fitted k_stretch_v_dyn_per_cm)"
          --k-shear "$(fitted k_shear_dyn_per_cm)")
for p in stockinette garter rib2x2; do
  for d in ${sheet_directions//,/ }; do
    run=$(sheet_run $p $d)
    ended "$run" || $k stretch --from "$(relaxed_knit "$(relax_dir $p $d)")" --sheet \
      "${material[@]}" --direction $d --to "$(strain_of $d)" --speed "$speed" -q --overwrite \
      --out "$run" || true
  done
done

for d in course wale bias; do
  sheets=()
  case ",$sheet_directions," in
    *,$d,*) sheets=($(sheet_run stockinette $d) $(sheet_run garter $d) $(sheet_run rib2x2 $d)) ;;
  esac
  $k stretch $(yarn_run stockinette $d) $(yarn_run garter $d) $(yarn_run rib2x2 $d) \
    "${sheets[@]}" --plot "$root/curves_$d.png"
done
# each knit beside its sheet at the end of the course pull
for p in stockinette garter rib2x2; do
  last=$(ls $root/${p}_course/frames/*.kstate | sort | tail -n 1)
  slast=$(ls $root/${p}_course_sheet/frames/*.kstate | sort | tail -n 1)
  $k render --compare "$last" "$slast" --labels "$p yarn,$p sheet" --color-rows \
    --size 800x600 --out "$root/${p}_course_yarn_vs_sheet.png"
done
echo "stretch_tests: curves in $root/curves_{course,wale,bias}.png, renders in $root/*_yarn_vs_sheet.png"
