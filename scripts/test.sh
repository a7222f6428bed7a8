#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite.
# Besides the build's packages the suite needs pytest (the Python module's tests) and the
# real readers it opens our exports in: Blender (OBJ, PLY; Debian's blender, about 106 MB
# to download, 440 MB installed, once), Assimp (glTF; assimp-utils), VTK (VTP, as ParaView
# reads it; python3-vtk9), Chromium (the viewer page, headless) and three.js's USDA parser
# (the .usda; run by Debian's nodejs, fetched with npm pack by scripts/fetch-usda-parser.sh).
# KNIT_SKIP_READERS=1 (or KNIT_SKIP_BLENDER=1) neither installs the readers nor runs the
# tests that need them. The docs site is built too (scripts/docs.sh, warnings as errors).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
tools=(python3-pytest)
skip=${KNIT_SKIP_READERS:-${KNIT_SKIP_BLENDER:-0}}
if [ -z "$skip" ] || [ "$skip" = 0 ]; then
  tools+=(blender assimp-utils python3-vtk9 chromium nodejs)
fi
bash scripts/apt-install.sh --why "test (pytest and the readers of the exports)" "${tools[@]}"
# the docs site, warnings as errors: a broken link or reference fails here
bash scripts/docs.sh
if [ -z "$skip" ] || [ "$skip" = 0 ]; then bash scripts/fetch-usda-parser.sh; fi
ctest --test-dir "${KNIT_BUILD_DIR:-build}" -j "$(nproc)" --output-on-failure "$@"
