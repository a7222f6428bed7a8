#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
ctest --test-dir "${KNIT_BUILD_DIR:-build}" -j "$(nproc)" --output-on-failure "$@"
