"""The ``knit-params`` directive: the table of the yarn model's parameters, from the program.

It runs ``knitsim params --json`` (the build's program, $KNIT_BUILD_DIR/knitsim, default
build/knitsim), which prints the parameter table that src/knit/model/params.def declares:
the page cannot drift from the code. A missing program fails the docs build naming it.
"""
import json
import os
import subprocess
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive

ROOT = Path(__file__).resolve().parents[2]


def number(x):
    return f"{x:g}" if isinstance(x, float) else json.dumps(x) if isinstance(x, bool) else str(x)


def read_params():
    build = Path(os.environ.get("KNIT_BUILD_DIR", ROOT / "build")).resolve()
    program = build / "knitsim"
    if not program.exists():
        raise RuntimeError(f"docs/_ext/knit_params.py: {program} is not built (scripts/setup.sh)")
    table = json.loads(subprocess.run([str(program), "params", "--json"], check=True,
                                      capture_output=True, text=True).stdout)
    rows = []
    for p in table:
        if "range" in p:
            span = f"{number(p['range'][0])} … {number(p['range'][1])}"
        elif "choices" in p:
            span = ", ".join(p["choices"])
        else:
            span = "true, false"
        default, relax = (p["default"], p["relaxation"])
        rows.append((p["name"], p["unit"], span, number(default) if not isinstance(default, str)
                     else default, number(relax) if not isinstance(relax, str) else relax,
                     p["doc"]))
    return rows


class KnitParams(Directive):
    has_content = False

    def run(self):
        header = ("parameter", "unit", "working range", "simulation", "relaxation", "meaning")
        rows = read_params()
        table = nodes.table()
        group = nodes.tgroup(cols=len(header))
        table += group
        for width in (14, 10, 12, 8, 8, 48):
            group += nodes.colspec(colwidth=width)

        def row(cells, literal_first):
            r = nodes.row()
            for i, text in enumerate(cells):
                entry = nodes.entry()
                entry += nodes.paragraph(
                    "", "", nodes.literal(text, text) if (i == 0 and literal_first) else nodes.Text(text))
                r += entry
            return r

        head = nodes.thead()
        head += row(header, False)
        group += head
        body = nodes.tbody()
        for cells in rows:
            body += row(cells, True)
        group += body
        return [table]


def setup(app):
    app.add_directive("knit-params", KnitParams)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
