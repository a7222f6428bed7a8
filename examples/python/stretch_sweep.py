"""Stretch one relaxed knit along the course at several speeds, with and without yarn
friction, and compare the forces.

    /usr/bin/python3 examples/python/stretch_sweep.py

Pulls the shipped relaxed 12 × 12 stockinette to 20 % strain at 2, 1 and 0.5 cm/s, once
with the paper's model (viscous damping only) and once with yarn–yarn Coulomb friction
0.3 in place of the non-rigid damping filter, and prints the moving clamp's force at 5,
10, 15 and 20 % strain (dyn). The paper's model loses about a quarter of its force at each
halving of the speed; with friction the curve hardly changes. About 10 minutes on 2 cores.
"""
import pathlib

import numpy as np

import knitsim

knit = pathlib.Path(__file__).resolve().parents[1] / "knits" / "stockinette_12x12.kstate"
models = {
    "paper (damping)": None,
    "yarn friction 0.3": {"yarn_friction": 0.3, "alpha_small": 0, "alpha_large": 0},
}

marks = np.array([0.05, 0.10, 0.15, 0.20])
print("model               speed (cm/s)  force at strain " + "  ".join(f"{e:.2f}" for e in marks))
for name, params in models.items():
    for speed in (2.0, 1.0, 0.5):
        r = knitsim.stretch(str(knit), direction="course", to=0.2, speed=speed, params=params)
        c = r["curve"]
        force = np.interp(marks, c["strain"], c["force_moving"])
        print(f"{name:18s}  {speed:12.1f}   " + "  ".join(f"{f:15.0f}" for f in force))
