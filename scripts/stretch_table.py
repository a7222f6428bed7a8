#!/usr/bin/env python3
"""A Markdown table of stretch runs (directories written by `knitsim stretch`), one row each.

    scripts/stretch_table.py out/stretch/42x32/friction_0.3/*_course [--strains 0.1,0.25,0.5,1]

Columns: pattern and direction; the force on the moving clamp along the pull at each strain
asked (dyn), interpolated in stretch.csv, and per course row (course pulls) or per wale
column (wale pulls); the width across the pull at strains 0.25 and 0.5 against strain 0;
the strain where the curve stiffens (summary.json); the first strain where yarns came within
half the contact distance (min_contact_distance < 0.5), where the contact penalty has given
way; and the run's wall time. A strain the run did not reach is left as "–".
"""
import argparse
import csv
import json
import os
import sys


def interpolate(xs, ys, x):
    if not xs or x < xs[0] or x > xs[-1]:
        return None
    for k in range(1, len(xs)):
        if xs[k] >= x:
            x0, x1 = xs[k - 1], xs[k]
            if x1 == x0:
                return ys[k]
            return ys[k - 1] + (ys[k] - ys[k - 1]) * (x - x0) / (x1 - x0)
    return ys[-1]


def number(v, digits=0):
    if v is None:
        return "–"
    return f"{v:,.{digits}f}"


def row_of(run, strains):
    with open(os.path.join(run, "summary.json")) as f:
        s = json.load(f)
    with open(os.path.join(run, "stretch.csv")) as f:
        rows = [r for r in csv.DictReader(f)]
    if not rows:
        raise ValueError(f"{run}/stretch.csv has no rows")
    # the first pull only (a cycled run comes back): rows up to the largest strain
    peak = max(range(len(rows)), key=lambda k: float(rows[k]["strain"]))
    rows = rows[: peak + 1]
    e = [float(r["strain"]) for r in rows]
    force = [float(r["force_moving_dyn"]) for r in rows]
    width = [float(r["width_cm"]) for r in rows]
    d = [float(r["min_contact_distance"]) for r in rows]
    direction = s.get("direction", "?")
    per = {"course": s.get("rows"), "wale": s.get("cols")}.get(direction)
    cells = [f"{s.get('pattern', '?')} {direction}" + (" (sheet)" if s.get("model") == "sheet" else "")]
    for x in strains:
        f = interpolate(e, force, x)
        text = number(f)
        if f is not None and per:
            text += f" ({number(f / per)})"
        cells.append(text)
    w0 = width[0]
    for x in (0.25, 0.5):
        w = interpolate(e, width, x)
        cells.append("–" if w is None or not w0 else f"{100 * (w / w0 - 1):+.0f} %")
    stretch = s.get("stretch", {})
    cells.append(number(stretch.get("stiffening_strain"), 2))
    squeezed = next((x for x, dd in zip(e, d) if 0 <= dd < 0.5), None)
    cells.append(number(squeezed, 2))
    cells.append(number(s.get("wall_time_s")) + " s")
    return cells


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", help="stretch run directories")
    p.add_argument("--strains", default="0.1,0.25,0.5,1", help="strains of the force columns")
    a = p.parse_args()
    try:
        strains = [float(x) for x in a.strains.split(",")]
    except ValueError:
        sys.exit(f"stretch_table: --strains: expected numbers separated by commas, got '{a.strains}'")
    head = (["run"] + [f"force at {x:g} (per row/column), dyn" for x in strains]
            + ["width at 0.25", "width at 0.5", "stiffens at", "d < 0.5 from", "wall time"])
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for run in a.runs:
        try:
            print("| " + " | ".join(row_of(run, strains)) + " |")
        except (OSError, ValueError, KeyError) as e:
            sys.exit(f"stretch_table: {run}: {e}")


if __name__ == "__main__":
    main()
