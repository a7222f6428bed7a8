# Sphinx configuration of knitsim's docs site (MyST Markdown, furo, Breathe, autodoc).
# Build it with scripts/docs.sh, which runs Doxygen first and passes -W --keep-going -n.
# KNIT_BUILD_DIR: the build folder holding python/knitsim*.so (default ../build from here);
# KNIT_DOXYGEN_XML: Doxygen's XML (default $KNIT_BUILD_DIR/docs/doxygen/xml).
import os
import sys
from pathlib import Path

here = Path(__file__).resolve().parent
root = here.parent
build = Path(os.environ.get("KNIT_BUILD_DIR", root / "build")).resolve()
sys.path.insert(0, str(build / "python"))
sys.path.insert(0, str(here / "_ext"))

project = "knitsim"
author = "the knitsim authors"
copyright = "knitsim authors"
release = ""
for line in (root / "CMakeLists.txt").read_text().splitlines():
    if line.startswith("project(knitsim VERSION"):
        release = line.split()[2]
version = release

extensions = [
    "myst_parser",
    "breathe",
    "sphinx.ext.autodoc",
    "knit_params",
]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_ext", "Thumbs.db", ".DS_Store"]
myst_enable_extensions = ["dollarmath"]
# anchors for the headings, so that page.md#section links resolve (GitHub makes the same)
myst_heading_anchors = 3
suppress_warnings = []

html_theme = "furo"
html_title = f"knitsim {release}"
html_static_path = []

breathe_projects = {
    "knitsim": os.environ.get("KNIT_DOXYGEN_XML", str(build / "docs" / "doxygen" / "xml"))
}
breathe_default_project = "knitsim"
breathe_default_members = ("members",)
cpp_index_common_prefix = ["knit::"]

autodoc_member_order = "bysource"
autodoc_typehints = "signature"

# nitpicky (-n): pybind11 signatures and Eigen/std types have no targets of their own
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|numpy\..*|Iterator|Sequence|Optional|Union|Callable|object|os\.PathLike|knitsim\..*)"),
    (r"cpp:.*", r"(std|Eigen|nlohmann|tbb|RTC|openvdb)(::.*)?|u?int\d+_t|size_t|ptrdiff_t|StiffSolver::RowMajorMatrix|RowMajorMatrix"),
    # the SIMD lane helpers (energy/lanes.hpp), left out of the pages (docs/Doxyfile)
    (r"cpp:.*", r"lanes(::.*)?|VecD|VecL"),
]


# The module's docstrings are plain text (pybind11), not reStructuredText: escape the
# characters reST would read as markup (|C| as a substitution, * as emphasis).
def _plain_docstring(app, what, name, obj, options, lines):
    for i, line in enumerate(lines):
        lines[i] = line.replace("\\", "\\\\").replace("|", "\\|").replace("*", "\\*")


def setup(app):
    app.connect("autodoc-process-docstring", _plain_docstring)
