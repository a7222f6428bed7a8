"""Stretch one relaxed knit along the course at several speeds and compare the forces.

    /usr/bin/python3 examples/python/stretch_sweep.py [OUT_DIR]

Relaxes a 6 × 6 stockinette, saves it, pulls it to 20 % strain at 2, 1 and 0.5 cm/s, and
prints the moving clamp's force at 5, 10, 15 and 20 % strain (dyn) — how far the curve is
from quasi-static. A few minutes on 2 cores.
"""
import pathlib
import sys

import numpy as np

import knitsim

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "out/python_sweep")
out.mkdir(parents=True, exist_ok=True)
knit = knitsim.relax("stockinette", rows=6, cols=6, max_time=0.5)
knit.save(str(out / "relaxed.kstate"))

marks = np.array([0.05, 0.10, 0.15, 0.20])
print("speed (cm/s)  force at strain " + "  ".join(f"{e:.2f}" for e in marks))
for speed in (2.0, 1.0, 0.5):
    r = knitsim.stretch(str(out / "relaxed.kstate"), direction="course", to=0.2, speed=speed)
    c = r["curve"]
    force = np.interp(marks, c["strain"], c["force_moving"])
    print(f"{speed:11.1f}   " + "  ".join(f"{f:15.0f}" for f in force))
