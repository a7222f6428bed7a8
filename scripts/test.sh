#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite.
# Besides the build's packages the suite needs Blender, which reads our OBJ and PLY
# exports (Debian's blender: about 106 MB to download, 440 MB installed, once).
# KNIT_SKIP_BLENDER=1 neither installs it nor runs the tests that need it.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# pytest runs the Python module's suite (python/tests) as one of the tests
bash scripts/apt-install.sh --why test python3-pytest
if [ "${KNIT_SKIP_BLENDER:-0}" = 0 ]; then
  bash scripts/apt-install.sh --why test blender
fi
ctest --test-dir "${KNIT_BUILD_DIR:-build}" -j "$(nproc)" --output-on-failure "$@"
