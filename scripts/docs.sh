#!/usr/bin/env bash
# Builds the docs site (docs/, Sphinx + MyST + furo, the C++ API from Doxygen through
# Breathe, the Python API from the built module's docstrings) into build/docs/html.
# Warnings are errors, of Doxygen and of Sphinx (-W --keep-going -n: a broken link,
# reference or heading fails the build). Needs the build's Python module
# (build/python/knitsim*.so; scripts/setup.sh builds it). Installs the Debian packages
# it needs when they are missing. KNIT_BUILD_DIR: the build folder (default build).
# Usage: scripts/docs.sh [extra sphinx-build options]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/apt-install.sh --why "docs (Sphinx, MyST, furo, Breathe, Doxygen)" \
  python3-sphinx python3-myst-parser furo python3-breathe doxygen
build_dir=$(realpath -m "${KNIT_BUILD_DIR:-build}")
if ! ls "$build_dir"/python/knitsim*.so >/dev/null 2>&1; then
  echo "docs: no Python module in $build_dir/python (build first: scripts/setup.sh)" >&2
  exit 1
fi
out=$build_dir/docs
mkdir -p "$out/doxygen"
# Doxygen: XML of the headers in src/knit (docs/Doxyfile), any warning fails
# a fresh XML and a fresh Sphinx environment (Breathe caches the XML files it read)
rm -rf "$out/doxygen/xml" "$out/doctrees"
KNIT_DOXYGEN_OUT=$out/doxygen doxygen docs/Doxyfile
/usr/bin/python3 docs/_ext/strip_file_refs.py "$out/doxygen/xml"
# the README's links into docs/ (read on GitHub, outside the site)
/usr/bin/python3 docs/_ext/check_readme_links.py README.md
# Sphinx from Debian's python3 (where its packages are), whatever python3 is first on PATH
KNIT_BUILD_DIR=$build_dir KNIT_DOXYGEN_XML=$out/doxygen/xml \
  /usr/bin/python3 -m sphinx -b html -W --keep-going -n -q -j auto \
  -d "$out/doctrees" docs "$out/html" "$@"
echo "docs: $out/html/index.html"
