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
"$tinsmith" tin config/red-butte.toml -o out/red-butte.tin --report out/red-butte.report.json
echo
echo "-- validate"
"$tinsmith" validate out/red-butte.tin
echo
echo "-- info"
"$tinsmith" info out/red-butte.tin
echo
echo "-- export OBJ (full precision) and a 10 m GeoTIFF heightmap"
"$tinsmith" export out/red-butte.tin --format obj -o out/red-butte.obj
"$tinsmith" export out/red-butte.tin --format tif --cell 10 -o out/red-butte.tif
echo "-- a shaded-relief picture of the TIN: out/red-butte-hillshade.png"
gdaldem hillshade -q -multidirectional -compute_edges out/red-butte.tif out/red-butte-hillshade.tif
gdal_translate -q -of PNG out/red-butte-hillshade.tif out/red-butte-hillshade.png
echo "-- query the TIN at the middle of the area"
"$tinsmith" query out/red-butte.tin 434000 4516000

echo
echo "== 2. level of detail: multilevel least squares (book Alg. 8.1) over the DEM cells, max error 5 m"
"$tinsmith" fit "$data/dem.tif" --tolerance 5 --lambda 0.1 --criterion error \
  -o out/red-butte-fit.tin --stats out/red-butte-fit.stats.json
"$tinsmith" export out/red-butte-fit.tin --format tif --cell 10 -o out/red-butte-fit.tif
gdaldem hillshade -q -multidirectional -compute_edges out/red-butte-fit.tif out/red-butte-fit-hillshade.tif
gdal_translate -q -of PNG out/red-butte-fit-hillshade.tif out/red-butte-fit-hillshade.png
echo "-- shaded relief of the fitted surface: out/red-butte-fit-hillshade.png"

echo
echo "== 3. the whole job: config/red-butte.toml → out/red-butte.3dtiles (+ out/red-butte.tin, as in 1)"
"$tinsmith" build config/red-butte.toml
"$tinsmith" info out/red-butte.3dtiles
echo "== 4. server: http://127.0.0.1:8080/"
missing+=("server (tinsmith serve)")

echo
echo "Not built yet, so not run:"
printf '  - %s\n' "${missing[@]}"
