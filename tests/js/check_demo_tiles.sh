#!/usr/bin/env bash
# The demo's tiles judged by the reference implementations (ctest
# JsCheckers.RedButte): Red Butte's TIN tiled by `tinsmith tile` into a Draco
# directory store, its --compression none twin and a .3dtiles archive; then
# the Khronos validator, draco3dgltf against the twin and the tileset rules
# (check_tiles.mjs), the archive against 3d-tiles-tools (check_archive.mjs)
# and CesiumJS in headless Chromium (cesium_smoke.mjs, screenshot kept in
# OUT). Usage: check_demo_tiles.sh TINSMITH_BINARY OUT_DIR
set -euo pipefail
bin=$1
out=$2
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
if [[ ! -d "$here/node_modules/gltf-validator" ]]; then
  echo "tests/js/node_modules is missing: run tools/setup.sh" >&2
  exit 1
fi
rm -rf "$out"
mkdir -p "$out"
"$bin" tin "$root/config/red-butte.toml" -o "$out/red-butte.tin" -q
tile=("$bin" tile "$out/red-butte.tin" --tolerance 5 --max-zoom 5 -q)
"${tile[@]}" -o "$out/draco"
"${tile[@]}" -o "$out/plain" --compression none
"${tile[@]}" -o "$out/red-butte.3dtiles"
node "$here/check_tiles.mjs" "$out/draco" --plain "$out/plain"
node "$here/check_tiles.mjs" "$out/plain"
node "$here/check_archive.mjs" "$out/red-butte.3dtiles" "$out/draco"
timeout 300 node "$here/cesium_smoke.mjs" "$out/draco" --out "$out/cesium.png" --timeout 180
