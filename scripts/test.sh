#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite.
# Besides the build's packages the suite needs pytest (the Python module's tests) and the
# real readers it opens our exports in: Blender (OBJ, PLY; Debian's blender, about 106 MB
# to download, 440 MB installed, once), Assimp (glTF; assimp-utils), VTK (VTP, as ParaView
# reads it; python3-vtk9) and Chromium (the viewer page, headless). KNIT_SKIP_READERS=1 (or
# KNIT_SKIP_BLENDER=1) neither installs the readers nor runs the tests that need them.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
bash scripts/apt-install.sh --why test python3-pytest
skip=${KNIT_SKIP_READERS:-${KNIT_SKIP_BLENDER:-0}}
if [ -z "$skip" ] || [ "$skip" = 0 ]; then
  bash scripts/apt-install.sh --why "test (readers of the exports)" blender assimp-utils python3-vtk9 chromium
fi
ctest --test-dir "${KNIT_BUILD_DIR:-build}" -j "$(nproc)" --output-on-failure "$@"
