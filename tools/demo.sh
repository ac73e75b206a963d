#!/usr/bin/env bash
# README command 1: install, build, and run the whole pipeline on the bundled
# Red Butte sample (../shared/data/red-butte), then serve it. Each stage that
# is not built yet is named plainly; nothing is faked.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/setup.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/release -j "$(nproc)" --target tinsmith

tinsmith=build/release/bin/tinsmith
data=../shared/data/red-butte
mkdir -p out
"$tinsmith" --version

missing=()
echo
echo "== 1. ingest + TIN: $data → out/red-butte.tin"
missing+=("TIN from config (tinsmith tin config/red-butte.toml)")
echo "== 2. tiles: out/red-butte.tin → out/red-butte.3dtiles"
missing+=("tiles (tinsmith tile)")
echo "== 3. server: http://127.0.0.1:8080/"
missing+=("server (tinsmith serve)")

echo
echo "Not built yet, so not run:"
printf '  - %s\n' "${missing[@]}"
