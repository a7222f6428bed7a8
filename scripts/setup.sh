#!/usr/bin/env bash
# Installs the Debian packages knitsim needs (only those missing) and builds it in
# Release into build/. Idempotent and quiet when everything is already there.
# Usage: scripts/setup.sh [--install-only]   (--install-only: the packages, no build)
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libtbb-dev libembree-dev nlohmann-json3-dev libcli11-dev
  zlib1g-dev libstb-dev libtinygltf-dev libgtest-dev libgmock-dev libbenchmark-dev
  libopenvdb-dev libboost-iostreams-dev
  ffmpeg gnuplot-nox clang-format
  python3-dev python3-numpy pybind11-dev libjs-three libfreetype-dev fonts-dejavu-core
  python3-distributed python3-pandas python3-tqdm
)
bash scripts/apt-install.sh --why setup "${packages[@]}"
[ "${1:-}" != --install-only ] || exit 0

build_dir=${KNIT_BUILD_DIR:-build}
jobs=${KNIT_JOBS:-$(nproc)}
if [ ! -f "$build_dir/build.ninja" ]; then
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release ${KNIT_CMAKE_ARGS:-} >/dev/null
fi
# ninja prints one line per file; keep the terminal to errors and the final line
if ! cmake --build "$build_dir" -j "$jobs" >"$build_dir/build.log" 2>&1; then
  cat "$build_dir/build.log"
  echo "setup: build failed (log: $build_dir/build.log)" >&2
  exit 1
fi

# the Python module and its sweep layer (python3-distributed), for Debian's python3
# (`import knitsim` from anywhere): copied into its site-packages folder for local modules;
# PYTHONPATH=build/python works without it
module=$(ls "$build_dir"/python/knitsim*.so 2>/dev/null | head -n 1 || true)
if [ -n "$module" ]; then
  site=$(/usr/bin/python3 -c 'import sysconfig; print(sysconfig.get_path("platlib"))')
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  if ! { "${sudo_cmd[@]}" mkdir -p "$site" &&
    "${sudo_cmd[@]}" install -m 644 "$module" "$build_dir/python/knitsim_sweep.py" "$site/"; }; then
    echo "setup: could not install the Python module into $site;" \
      "use PYTHONPATH=$build_dir/python" >&2
  fi
fi
