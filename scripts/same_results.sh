#!/usr/bin/env bash
# Whether a change kept knitsim's results: runs the same short jobs with two builds' knitsim
# (relaxations flat, bound off and cast on, in the round, from a knitout program, by FIRE
# with contact reuse; a scene; a stretch; an OBJ export) and compares every final state's
# positions and velocities bit for bit (and the export byte for byte). A refactor should
# print "identical" on every line. Takes about 10 s.
#
#   scripts/same_results.sh OLD_KNITSIM NEW_KNITSIM [OUT]
#
# e.g. build the last landed commit in a worktree (`git worktree add /tmp/base COMMIT`,
# `cmake -S /tmp/base -B /tmp/base/build -G Ninja -DCMAKE_BUILD_TYPE=Release
# -DKNIT_BUILD_TESTS=OFF -DKNIT_BUILD_PYTHON=OFF`, `cmake --build /tmp/base/build --target
# knitsim_app`), then `scripts/same_results.sh /tmp/base/build/knitsim build/knitsim`.
# Reads the states with this build's Python module (build/python). Exits 1 on a difference.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { sed -n '2,14p' "$0"; exit 1; }
out=${3:-out/same-results}
run_all() {
  local k=$1 o=$2
  mkdir -p "$o"
  "$k" relax stockinette --rows 12 --cols 12 --max-time 0.05 --out "$o/st" --overwrite -q --no-frames
  "$k" relax rib2x2 --rows 8 --cols 10 --max-time 0.05 --bind-off --cast-on --out "$o/rib" \
    --overwrite -q --no-frames
  "$k" relax seed --round --rows 6 --cols 8 --max-time 0.02 --out "$o/round" --overwrite -q --no-frames
  "$k" relax tests/data/knitout/Tutorial3_wafflestitch.k --max-time 0.01 --out "$o/waffle" \
    --overwrite -q --no-frames
  "$k" relax garter --rows 10 --cols 10 --fire --integrator imex-contact --time-step 6e-4 \
    --max-time 0.05 --out "$o/fire" --overwrite -q --no-frames
  "$k" simulate examples/drape_sphere.json --knit "$o/st/final.kstate" --duration 0.02 \
    --out "$o/drape" --overwrite -q
  "$k" stretch --from "$o/st/final.kstate" --direction course --to 0.02 --no-render \
    --out "$o/pull" --overwrite -q --no-frames
  "$k" export "$o/st/final.kstate" --format obj --out "$o/st.obj"
}
run_all "$1" "$out/old" >/dev/null
run_all "$2" "$out/new" >/dev/null
PYTHONPATH="${KNIT_BUILD_DIR:-build}/python" /usr/bin/python3 - "$out" <<'PY'
import sys
import numpy as np
import knitsim
out = sys.argv[1]
differ = 0
for run in ["st", "rib", "round", "waffle", "fire", "drape", "pull"]:
    a = knitsim.read_state(f"{out}/old/{run}/final.kstate").state
    b = knitsim.read_state(f"{out}/new/{run}/final.kstate").state
    if a.q.shape == b.q.shape and np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v):
        print(f"{run}: identical")
    else:
        differ += 1
        d = np.abs(a.q - b.q).max() if a.q.shape == b.q.shape else float("nan")
        print(f"{run}: DIFFERENT (largest position difference {d:.3e} cm)")
same = open(f"{out}/old/st.obj", "rb").read() == open(f"{out}/new/st.obj", "rb").read()
print("st.obj:", "identical" if same else "DIFFERENT")
sys.exit(1 if differ or not same else 0)
PY
