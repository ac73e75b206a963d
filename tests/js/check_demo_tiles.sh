#!/usr/bin/env bash
# The demo's tiles judged by the reference implementations (ctest
# JsCheckers.RedButte): Red Butte built as the demo builds it (`tinsmith
# build config/red-butte.toml`, its [tiles] keys) into a Draco directory
# store, its --compression none twin and a .3dtiles archive; then
# the Khronos validator, draco3dgltf against the twin and the tileset rules
# (check_tiles.mjs), the archive against 3d-tiles-tools (check_archive.mjs)
# and CesiumJS in headless Chromium (cesium_smoke.mjs, screenshot kept in
# OUT); then a plan view of each zoom's mesh (draw_zooms.mjs, OUT/zoom-Z.png,
# about 5 s). Usage: check_demo_tiles.sh TINSMITH_BINARY OUT_DIR
set -euo pipefail
source "$(dirname "$0")/script_prelude.sh"
# Each store in its own folder under one name: the build record names the
# TIN beside it (red-butte.tin), so the archive and the Draco directory hold
# the same bytes.
mkdir -p "$out/draco" "$out/plain"
build=("$bin" build "$root/config/red-butte.toml" -q)
draco="$out/draco/red-butte"
plain="$out/plain/red-butte"
"${build[@]}" -o "$draco"
"${build[@]}" -o "$plain" --compression none
"${build[@]}" -o "$out/red-butte.3dtiles"
node "$here/check_tiles.mjs" "$draco" --plain "$plain"
node "$here/check_tiles.mjs" "$plain"
node "$here/check_archive.mjs" "$out/red-butte.3dtiles" "$draco"
timeout 300 node "$here/cesium_smoke.mjs" "$draco" --out "$out/cesium.png" --timeout 180
node "$here/draw_zooms.mjs" "$plain" "$out/zoom-"
