#!/usr/bin/env bash
# Fetches three.js's USDA parser (one file of the `three` package, pinned and checked against
# its sha512) into third_party/three-usda/. The tests read our .usda exports with it: an
# independent parser of the USD text format, as Debian has no USD library. The package comes
# through npm itself (`npm pack`), so whatever registry the machine's npm is configured for
# serves it. Needs Node.js and npm (Debian's nodejs and npm; installed if missing).
# Usage: scripts/fetch-usda-parser.sh   (does nothing when the file is already there)
set -euo pipefail
cd "$(dirname "$0")/.."
version=0.187.0
integrity='sha512-Qiu7R+Cmh8CstZsY1uJOSWnVlfo7ZtNLV7mF8Jltk3LB3AtDu9cRZlcnRKkAk8Y4z6KKw35z7Y7Urd7jWY8etA=='
dest=third_party/three-usda
[ -f "$dest/USDAParser.js" ] && [ "$(cat "$dest/VERSION" 2>/dev/null)" = "$version" ] && exit 0
why="the USD parser the tests use"
command -v node >/dev/null || bash scripts/apt-install.sh --why "$why" nodejs
# Debian's nodejs does not bring npm (nodesource's does)
command -v npm >/dev/null || bash scripts/apt-install.sh --why "$why" npm
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# in the temporary folder, so that no package.json or .npmrc of a folder above is read
if ! (cd "$tmp" && npm pack "three@$version" --ignore-scripts --loglevel=error \
  --pack-destination "$tmp" >"$tmp/name" 2>"$tmp/npm.log"); then
  cat "$tmp/npm.log" >&2
  echo "fetch-usda-parser: npm pack three@$version failed (registry: $(npm config get registry))" >&2
  exit 1
fi
tgz="$tmp/$(tail -n 1 "$tmp/name")"
# the pinned checksum, not only the registry's: a changed or substituted package is refused
got=$(node -e 'const c = require("node:crypto"), fs = require("node:fs");
process.stdout.write("sha512-" + c.createHash("sha512").update(fs.readFileSync(process.argv[1])).digest("base64"));' "$tgz")
if [ "$got" != "$integrity" ]; then
  echo "fetch-usda-parser: three@$version from $(npm config get registry) has checksum $got," \
    "not the pinned $integrity" >&2
  exit 1
fi
tar -xzf "$tgz" -C "$tmp" package/LICENSE package/examples/jsm/loaders/usd/USDAParser.js
mkdir -p "$dest"
cp "$tmp/package/examples/jsm/loaders/usd/USDAParser.js" "$tmp/package/LICENSE" "$dest/"
echo "$version" >"$dest/VERSION"
echo "fetch-usda-parser: three.js $version's USDAParser.js in $dest"
