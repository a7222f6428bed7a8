#!/usr/bin/env bash
# Installs the given Debian packages, only those not installed yet (quiet, no recommends).
# Usage: scripts/apt-install.sh [--why TEXT] PACKAGE...
# Used by setup.sh (build), test.sh (test-only tools) and fuzz.sh (clang's libFuzzer).
set -euo pipefail
why=setup
if [ "${1:-}" = --why ]; then
  why=$2
  shift 2
fi
missing=()
for p in "$@"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -gt 0 ] || exit 0
echo "$why: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
  "${missing[@]}" >/dev/null
