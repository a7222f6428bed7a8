#!/usr/bin/env bash
# Builds and runs knitsim's benchmarks: scripts/bench.sh
#   [step|relax|scaling|threads|contact|step_limit|time_to_solution|relax_to_rest|scarf]...
# (none: the first five). Each prints one JSON document; they are also saved under out/bench/.
#   relax_to_rest: 12×12 stockinette, garter and 2×2 rib relaxed from their generated
#   yarn by damped dynamics (explicit and IMEX) and by FIRE (IMEX; imex-contact without
#   and with contact reuse), to rest or 30 s simulated (about 17 minutes on 2 cores, 6 of
#   them the explicit stockinette; RELAX_ARGS
#   replaces the options, e.g. RELAX_ARGS="--patterns stockinette --methods fire:imex:3e-4";
#   with "--rows 42 --cols 32 --reference out/ref/rest" each rest shape is compared with
#   the long relaxations scripts/relax_reference.sh keeps there).
#   scarf: the 20×160 scarf of examples/scarf_on_plane.json falling onto the floor for
#   SCARF_TIME s (default 0.2: the impact and the first folds) with the explicit step at
#   the paper's 1/22500 s (the reference) and the IMEX step at 1e-4 and 2e-4 s. The
#   relaxed scarf it drops is made once into out/bench/scarf_relax (garter 160×20 relaxed
#   2 s with the IMEX step at 2.5e-4 s, about 7 minutes on 2 cores).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
mkdir -p out/bench
which=("$@")
[ ${#which[@]} -gt 0 ] || which=(step threads scaling relax contact)
for b in "${which[@]}"; do
  case "$b" in
    step|relax|scaling|threads|step_limit) args=() ;;
    # the ends' mass floor: imex-contact's large steps otherwise fail first at the light ends
    time_to_solution) args=(--end-mass-floor 0.5 --time 0.2) ;;
    relax_to_rest) read -r -a args <<< "${RELAX_ARGS:-}" ;;
    contact) args=(11264 20 2 5) ;;
    scarf)
      knit=out/bench/scarf_relax/final.kstate
      if ! grep -qs '"status": "ok"' out/bench/scarf_relax/summary.json; then
        echo "== relaxing the 20×160 garter scarf into out/bench/scarf_relax" >&2
        ./build/knitsim relax garter --rows 160 --cols 20 --max-time 2 --integrator imex \
          --time-step 2.5e-4 --no-frames -q --overwrite --out out/bench/scarf_relax
      fi
      echo "== scarf" >&2
      ./build/bench_time_to_solution --scene examples/scarf_on_plane.json --knit "$knit" \
        --time "${SCARF_TIME:-0.2}" --reference explicit:4.444444444444444e-05 \
        --runs imex:1e-4,imex:2e-4 | tee out/bench/scarf.json
      continue ;;
    *) echo "bench.sh: unknown benchmark '$b' (step, relax, scaling, threads, contact, step_limit, time_to_solution, relax_to_rest, scarf)" >&2; exit 1 ;;
  esac
  echo "== $b" >&2
  ./build/bench_$b "${args[@]}" | tee "out/bench/$b.json"
done
