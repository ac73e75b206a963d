#!/usr/bin/env bash
# Whole-TIN glb exports judged by the reference implementations (ctest
# JsCheckers.ExportGlb): the Red Butte TIN as the demo builds it (`tinsmith
# tin config/red-butte.toml`), exported with `tinsmith export --format glb`
# in both frames, Draco and plain, each checked by check_glb.mjs (Khronos
# validator, draco3dgltf, the Draco file against its plain twin). About 30 s.
# Usage: check_export_glb.sh TINSMITH_BINARY OUT_DIR
set -euo pipefail
source "$(dirname "$0")/script_prelude.sh"
tin="$out/red-butte.tin"
timeout 120 "$bin" tin "$root/config/red-butte.toml" -q -o "$tin"
for frame in ecef local; do
  geoid=()
  [[ $frame == ecef ]] && geoid=(--geoid egm96)  # as config/red-butte.toml's [tiles]
  for compression in draco none; do
    timeout 60 "$bin" export "$tin" --format glb --frame "$frame" --compression "$compression" \
      "${geoid[@]}" -o "$out/$frame-$compression.glb"
  done
  timeout 120 node "$here/check_glb.mjs" "$out/$frame-draco.glb" --plain "$out/$frame-none.glb"
  timeout 120 node "$here/check_glb.mjs" "$out/$frame-none.glb"
done
