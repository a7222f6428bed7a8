#!/usr/bin/env bash
# The paper's dynamic scenes, each reproducible with one command and resumable: run it
# again after an interruption (Ctrl-C, a killed session) and it goes on from the last
# state written. Long: run it in the background, e.g.
#   nohup scripts/scenes.sh scarf > out/scenes/scarf.log 2>&1 &
# Usage: scripts/scenes.sh scarf|long-scarf|leg-warmer|leg-warmer-mesh [--threads N]
#   scarf       relax a 20×160 garter scarf (2 s), drop it onto a plane
#               (examples/scarf_on_plane.json, 2 s), render the drop as a movie
#   long-scarf  relax a 20×400 garter scarf (2 s, IMEX step 2.5e-4 s), slide it down an
#               incline (examples/scarf_on_incline.json, 3 s), render it
#   leg-warmer  relax a 44×96 2×2-rib tube knit in the round (2 s), pull it over a foot
#               (examples/leg_warmer.json, 3 s), render it; leg-warmer-mesh: the same
#               with the foot as an OBJ mesh (examples/leg_warmer_mesh.json; hands 1 cm
#               further apart, IMEX step)
# Outputs in out/scenes/<name>_relax and out/scenes/<name>, movie in
# out/scenes/<name>/movie/animation.mp4.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:?usage: scripts/scenes.sh scarf|long-scarf|leg-warmer|leg-warmer-mesh [--threads N]}
threads=0
if [ "${2:-}" = --threads ]; then threads=${3:?--threads needs a number}; fi
knit_args=() relax_args=() seq_times=()
case $scene in
  scarf) knit_args=(garter --rows 160 --cols 20) file=examples/scarf_on_plane.json name=scarf relax=scarf ;;
  long-scarf) # 64k segments: the IMEX step (as the scene's own) makes its relaxation minutes, not hours
    knit_args=(garter --rows 400 --cols 20) relax_args=(--integrator imex --time-step 2.5e-4)
    file=examples/scarf_on_incline.json name=long_scarf relax=long_scarf ;;
  leg-warmer | leg-warmer-mesh)
    knit_args=(rib2x2 --round --rows 96 --cols 44) relax=leg_warmer seq_times=(0.5 1 1.5 2)
    if [ "$scene" = leg-warmer ]; then file=examples/leg_warmer.json name=leg_warmer
    else file=examples/leg_warmer_mesh.json name=leg_warmer_mesh; fi ;;
  *) echo "scenes: unknown scene '$scene' (scarf, long-scarf, leg-warmer or leg-warmer-mesh)" >&2; exit 2 ;;
esac
[ -x build/knitsim ] || scripts/setup.sh
k=./build/knitsim
relax_dir=out/scenes/${relax}_relax run_dir=out/scenes/$name
relax_time=2
mkdir -p out/scenes

# the last time written to a run's log (0 when none)
last_time() { [ -f "$1/log.csv" ] && tail -n 1 "$1/log.csv" | cut -d, -f1 | grep -E '^[0-9.e+-]+$' || echo 0; }
# the newest state of a run's frames
last_frame() { ls "$1"/frames/*.kstate 2>/dev/null | sort | tail -n 1; }

# 1. the relaxed knit
if [ ! -f "$relax_dir/relaxed.kstate" ]; then
  frame=$(last_frame "$relax_dir" || true)
  if [ -f "$relax_dir/summary.json" ] && grep -q '"status": "interrupted"' "$relax_dir/summary.json"; then
    frame=$relax_dir/final.kstate
  fi
  if [ -n "$frame" ]; then
    left=$(awk -v t="$(last_time "$relax_dir")" -v T=$relax_time 'BEGIN { l = T - t; print (l > 1e-6 ? l : 1e-6) }')
    echo "scenes: relaxation goes on from $frame ($left s left)"
    $k relax --resume "$frame" --max-time "$left" "${relax_args[@]}" -j "$threads" -q --out "$relax_dir"
  else
    $k relax "${knit_args[@]}" --max-time "$relax_time" "${relax_args[@]}" -j "$threads" -q \
      --overwrite --out "$relax_dir"
  fi
fi
# a relaxation that reached its time limit ends with status "ok" but writes no
# relaxed.kstate until it is at rest: take its final state as the knit
knit=$relax_dir/relaxed.kstate
[ -f "$knit" ] || knit=$relax_dir/final.kstate

# 2. the scene
if [ -f "$run_dir/summary.json" ] && grep -q '"status": "ok"' "$run_dir/summary.json"; then
  echo "scenes: $run_dir is done"
else
  frame=$(last_frame "$run_dir" || true)
  # an interrupted run (Ctrl-C, SIGTERM) left its last state in final.kstate
  if [ -f "$run_dir/summary.json" ] && grep -q '"status": "interrupted"' "$run_dir/summary.json"; then
    frame=$run_dir/final.kstate
  fi
  if [ -n "$frame" ]; then
    echo "scenes: the run goes on from $frame"
    $k simulate "$file" --knit "$knit" --resume "$frame" -j "$threads" -q --out "$run_dir"
  else
    $k simulate "$file" --knit "$knit" -j "$threads" -q --overwrite --out "$run_dir"
  fi
fi

# 3. pictures
$k render "$run_dir/final.kstate" --view scene --color-rows --size 1280x960 --out "$run_dir/final.png"
$k render "$run_dir/frames" --view scene --color-rows --size 640x480 --spp 2 --shadow-rays 2 \
  --ao-rays 2 --fps 30 --overwrite --out "$run_dir/movie"
# the movie's frames (time stamp, scale bar) at seq_times side by side: sequence.png
seq=
if [ ${#seq_times[@]} -gt 0 ]; then
  frames=$(ls "$run_dir"/movie/frame_*.png | wc -l)
  end=$(grep -o '"sim_time_s": [0-9.e+-]*' "$run_dir/summary.json" | cut -d' ' -f2)
  inputs=()
  for t in "${seq_times[@]}"; do
    i=$(awk -v t="$t" -v n="$frames" -v T="$end" 'BEGIN { printf "%04d", int(t * (n - 1) / T + 0.5) }')
    inputs+=(-i "$run_dir/movie/frame_$i.png")
  done
  # a white line between the panels
  n=${#seq_times[@]} filter=
  for ((p = 0; p < n; p++)); do
    if [ $p -lt $((n - 1)) ]; then filter+="[$p]pad=iw+6:ih:0:0:white[p$p];"; else filter+="[$p]null[p$p];"; fi
  done
  for ((p = 0; p < n; p++)); do filter+="[p$p]"; done
  ffmpeg -loglevel error -y "${inputs[@]}" -filter_complex "${filter}hstack=inputs=$n" \
    "$run_dir/sequence.png"
  seq=", $run_dir/sequence.png"
fi
echo "scenes: $scene done: $run_dir/summary.json, $run_dir/final.png$seq, $run_dir/movie/animation.mp4"
