"""The ``knit-cpp-api`` directive: the C++ API, one section per folder of src/knit.

It lists the headers under src/knit (so that a moved or new header needs no edit here) and
emits a Breathe ``doxygenfile`` directive for each, which renders what Doxygen read from it
(docs/Doxyfile).
"""
from pathlib import Path

from docutils.parsers.rst import Directive
from docutils.statemachine import StringList
from docutils import nodes

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / "src"


class KnitCppApi(Directive):
    has_content = False

    def run(self):
        lines = []
        folders = sorted({p.parent for p in (SRC / "knit").rglob("*.hpp")})
        for folder in folders:
            rel = folder.relative_to(SRC).as_posix()
            title = rel + "/"
            lines += [title, "-" * len(title), ""]
            for header in sorted(folder.glob("*.hpp")):
                name = header.relative_to(SRC).as_posix()
                lines += [f".. doxygenfile:: {name}", "   :project: knitsim", ""]
        node = nodes.section()
        node.document = self.state.document
        self.state.nested_parse(StringList(lines, source="knit-cpp-api"), self.content_offset,
                                node, match_titles=True)
        return node.children


def setup(app):
    app.add_directive("knit-cpp-api", KnitCppApi)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
