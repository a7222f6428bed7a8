#!/usr/bin/env python3
"""The library's layers, bottom up, and a check of its #include graph against them.

Each folder of src/knit belongs to one layer. A file may include headers of its own
folder, of folders in its own layer and of any lower layer; never of a higher one. No
two folders may include each other through any chain (no folder cycle), within a layer
or across. Only the presentation layer may include Embree or FreeType, whose code the
core library target (knit) does not link.

Usage: scripts/check_layers.py [SOURCE_DIR]   (prints every violation; exits 1 if any)
"""
import os
import re
import sys

# bottom up; docs/core.md describes each layer
LAYERS = [
    ("util", ["util"]),  # input limits, atomic writes, byte readers, processes, run directories
    ("knit graph", ["graph"]),  # loops, yarns and their front ends' machine (no physics)
    ("geometry", ["spline"]),  # B-spline basis and fits
    ("model", ["model"]),  # the immutable Model, State, StepData, the parameter table
    ("physics", ["energy", "contact", "constraints", "filters", "objects", "sheet"]),
    ("formats", ["io"]),  # files: states, imports, exports
    ("solver", ["solver"]),  # the step: stages, integrators, projection
    ("run", ["run"]),  # the run loop: log, summary, checkpoints, interrupt, resume, relaxation
    ("builders", ["pattern", "scene", "analysis"]),  # knits, scenes, measurements of shapes
    ("studies", ["recipes"]),  # relax, stretch, sheet fits
    ("presentation", ["present"]),  # render, plot, viewer, video
]
PRESENTATION_ONLY = re.compile(r"#include\s*[<\"](embree\d*/|ft2build\.h|freetype)")
INCLUDE = re.compile(r'#include\s*"knit/([A-Za-z0-9_]+)/')


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    src = os.path.join(root, "src", "knit")
    layer_of = {f: i for i, (_, folders) in enumerate(LAYERS) for f in folders}
    problems = []
    folders = sorted(d for d in os.listdir(src) if os.path.isdir(os.path.join(src, d)))
    for d in folders:
        if d not in layer_of:
            problems.append(f"src/knit/{d}/: a folder in no layer (add it to LAYERS in {__file__})")
    edges = {}  # folder -> {folder: first "file:line"}
    for d in folders:
        for dirpath, _, files in os.walk(os.path.join(src, d)):
            for name in sorted(files):
                if not name.endswith((".hpp", ".cpp", ".h", ".inc")):
                    continue
                path = os.path.join(dirpath, name)
                rel = os.path.relpath(path, root)
                with open(path, encoding="utf-8") as f:
                    for n, line in enumerate(f, 1):
                        if PRESENTATION_ONLY.search(line) and d not in LAYERS[-1][1]:
                            problems.append(f"{rel}:{n}: includes {line.split()[1]}, which only "
                                            f"the presentation layer may use")
                        m = INCLUDE.search(line)
                        if not m or m.group(1) == d:
                            continue
                        to = m.group(1)
                        edges.setdefault(d, {}).setdefault(to, f"{rel}:{n}")
                        if d in layer_of and to in layer_of and layer_of[to] > layer_of[d]:
                            problems.append(
                                f"{rel}:{n}: {d}/ ({LAYERS[layer_of[d]][0]}) includes "
                                f"{to}/ ({LAYERS[layer_of[to]][0]}), a higher layer")
    # folder cycles: a depth-first search that reports each cycle through its first edge
    state, stack, cycles = {}, [], set()

    def visit(u):
        state[u] = 1
        stack.append(u)
        for v in sorted(edges.get(u, {})):
            if state.get(v) == 1:
                cyc = stack[stack.index(v):] + [v]
                key = frozenset(cyc)
                if key not in cycles:
                    cycles.add(key)
                    where = ", ".join(edges[a][b] for a, b in zip(cyc, cyc[1:]))
                    problems.append("folder cycle " + " -> ".join(cyc) + " (" + where + ")")
            elif v not in state:
                visit(v)
        stack.pop()
        state[u] = 2

    for d in folders:
        if d not in state:
            visit(d)
    for p in problems:
        print(p)
    if problems:
        print(f"check_layers: {len(problems)} problem(s); the layers are in {__file__}")
        return 1
    print(f"check_layers: {len(folders)} folders in {len(LAYERS)} layers, "
          f"{sum(len(v) for v in edges.values())} arrows between folders, all downward, no cycle")
    return 0


if __name__ == "__main__":
    sys.exit(main())
