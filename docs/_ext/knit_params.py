"""The ``knit-params`` directive: the table of scene parameters, made from the library.

It reads the working ranges from ``param_ranges()`` (src/knit/model/params.cpp) and the
defaults and their one-line docs from the structs in src/knit/model/params.hpp, so that the
reference page cannot drift from the code. When the sources change shape so that a range
has no default or nothing is found, the docs build fails naming this file.
"""
import re
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive

ROOT = Path(__file__).resolve().parents[2]
CPP = ROOT / "src/knit/model/params.cpp"
HPP = ROOT / "src/knit/model/params.hpp"


def read_params():
    cpp = CPP.read_text()
    ranges = re.findall(r'\{"(\w+)",\s*([^,]+),\s*([^,]+),\s*"([^"]*)"\}', cpp)
    lines = HPP.read_text().splitlines()
    field = re.compile(r"^\s*(?:double|int|bool)\s+(\w+)\s*=\s*([^;]+);\s*(?:///<\s*(.*))?$")
    defaults, docs, relax = {}, {}, {}
    for i, line in enumerate(lines):
        m = field.match(line)
        if m:
            name = m.group(1)
            defaults[name] = m.group(2).strip()
            text = [m.group(3)] if m.group(3) else []
            if text:  # a trailing ///< comment and its continuation lines
                j = i + 1
                while j < len(lines) and lines[j].strip().startswith("///<"):
                    text.append(lines[j].strip()[4:].strip())
                    j += 1
            else:  # the /// block above the field
                j = i - 1
                while j >= 0 and lines[j].strip().startswith("///") and not lines[j].strip().startswith("///<"):
                    text.insert(0, lines[j].strip()[3:].strip())
                    j -= 1
            docs[name] = " ".join(text).replace("MODEL.md", "docs/model.md")
        m = re.match(r"^\s*p\.\w+\.(\w+)\s*=\s*([^;]+);", line)
        if m:
            relax[m.group(1)] = m.group(2).strip()
    if not ranges:
        raise RuntimeError(f"docs/_ext/knit_params.py: no param_ranges() table found in {CPP}")
    rows = []
    for name, lo, hi, unit in ranges:
        if name not in defaults:
            raise RuntimeError(f"docs/_ext/knit_params.py: no default for {name} in {HPP}")
        rows.append((name, unit, f"{lo.strip()} … {hi.strip()}", defaults[name],
                     relax.get(name, defaults[name]), docs[name]))
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
