#!/usr/bin/env bash
# Fetches three.js's USDA parser (one file of the `three` package from the npm registry,
# pinned and checked against the registry's sha512) into third_party/three-usda/. The
# tests read our .usda exports with it: an independent parser of the USD text format, as
# Debian has no USD library. Needs Node.js (Debian's nodejs; installed if missing).
# Usage: scripts/fetch-usda-parser.sh   (does nothing when the file is already there)
set -euo pipefail
cd "$(dirname "$0")/.."
version=0.187.0
integrity='sha512-Qiu7R+Cmh8CstZsY1uJOSWnVlfo7ZtNLV7mF8Jltk3LB3AtDu9cRZlcnRKkAk8Y4z6KKw35z7Y7Urd7jWY8etA=='
dest=third_party/three-usda
[ -f "$dest/USDAParser.js" ] && [ "$(cat "$dest/VERSION" 2>/dev/null)" = "$version" ] && exit 0
command -v node >/dev/null || bash scripts/apt-install.sh --why "the USD parser the tests use" nodejs
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
node -e '
const [url, out, want] = process.argv.slice(1);
const { createHash } = require("node:crypto");
(async () => {
  const r = await fetch(url);
  if (!r.ok) throw new Error(url + ": HTTP " + r.status);
  const bytes = Buffer.from(await r.arrayBuffer());
  const got = "sha512-" + createHash("sha512").update(bytes).digest("base64");
  if (got !== want) throw new Error(url + ": checksum " + got + " is not the registry'"'"'s " + want);
  require("node:fs").writeFileSync(out, bytes);
})().catch(e => { console.error("fetch-usda-parser: " + e.message); process.exit(1); });
' "https://registry.npmjs.org/three/-/three-$version.tgz" "$tmp/three.tgz" "$integrity"
tar -xzf "$tmp/three.tgz" -C "$tmp" package/LICENSE package/examples/jsm/loaders/usd/USDAParser.js
mkdir -p "$dest"
cp "$tmp/package/examples/jsm/loaders/usd/USDAParser.js" "$tmp/package/LICENSE" "$dest/"
echo "$version" >"$dest/VERSION"
echo "fetch-usda-parser: three.js $version's USDAParser.js in $dest"
