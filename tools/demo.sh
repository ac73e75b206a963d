#!/usr/bin/env bash
# README command 1: install, build, and run the whole pipeline on the bundled
# Red Butte sample (../shared/data/red-butte), then serve it with the viewer
# until Ctrl-C.
#   bash tools/demo.sh              # … and serve the viewer at http://127.0.0.1:8080/
#   bash tools/demo.sh --no-serve   # stop after the tiles (CI, scripts)
#   PORT=9000 bash tools/demo.sh    # serve on another port
set -euo pipefail
cd "$(dirname "$0")/.."

serve=1
for arg in "$@"; do
  case "$arg" in
    --no-serve) serve=0 ;;
    *) echo "demo: unknown option '$arg' (use --no-serve or nothing)" >&2; exit 2 ;;
  esac
done
port=${PORT:-8080}

bash tools/setup.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/release -j "$(nproc)" --target tinsmith

tinsmith=build/release/bin/tinsmith
data=../shared/data/red-butte
mkdir -p out
"$tinsmith" --version

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
echo "-- export the whole TIN as one Draco glTF on the globe (EGM96 heights, as the tiles)"
"$tinsmith" export out/red-butte.tin --format glb --geoid egm96 -o out/red-butte.glb
echo "   out/red-butte.glb: $(stat -c %s out/red-butte.glb) bytes, the whole TIN in one file (CesiumJS;"
echo "   --frame local for Blender and other DCC tools)"
echo "-- a shaded-relief picture of the TIN: out/red-butte-hillshade.png"
gdaldem hillshade -q -multidirectional -compute_edges out/red-butte.tif out/red-butte-hillshade.tif
gdal_translate -q -of PNG out/red-butte-hillshade.tif out/red-butte-hillshade.png
echo "-- query the TIN at the middle of the area"
"$tinsmith" query out/red-butte.tin 434000 4516000
echo "-- the DEM's cells as a TIN built block by block, as for more points than memory holds"
echo "   (the raster read in strips; each block triangulated with the cells within 2 × 80 m of"
echo "   it; triangles with a circumradius over 80 m, the hull's slivers, left out)"
"$tinsmith" tin --points "$data/dem.tif" --crs EPSG:26912 --block-points 4000 \
  --max-circumradius 80 -o out/red-butte-dem.tin
"$tinsmith" validate out/red-butte-dem.tin

echo
echo "== 2. level of detail: multilevel least squares (book Alg. 8.1) over the DEM cells, max error 5 m"
"$tinsmith" fit "$data/dem.tif" --tolerance 5 --lambda 0.1 --criterion error \
  -o out/red-butte-fit.tin --stats out/red-butte-fit.stats.json
"$tinsmith" export out/red-butte-fit.tin --format tif --cell 10 -o out/red-butte-fit.tif
gdaldem hillshade -q -multidirectional -compute_edges out/red-butte-fit.tif out/red-butte-fit-hillshade.tif
gdal_translate -q -of PNG out/red-butte-fit-hillshade.tif out/red-butte-fit-hillshade.png
echo "-- shaded relief of the fitted surface: out/red-butte-fit-hillshade.png"

echo
echo "== 3. the whole job: config/red-butte.toml → out/red-butte.3dtiles (+ out/red-butte.tin, as in 1):"
echo "   3D Tiles and Cesium terrain (quantized-mesh) in one store ([tiles] scheme = \"both\")"
"$tinsmith" build config/red-butte.toml
"$tinsmith" info out/red-butte.3dtiles

echo
if [ "$serve" -eq 0 ]; then
  echo "== 4. server: skipped (--no-serve); run: $tinsmith serve out/red-butte.3dtiles"
  exit 0
fi
echo "== 4. server and viewer (Ctrl-C stops it)"
echo
echo "   Open http://127.0.0.1:$port/ in a browser: Red Butte Canyon in 3-D (CesiumJS),"
echo "   the height, slope and coordinates under the cursor, profiles, the break lines."
echo "   The globe as tinsmith's Cesium terrain: http://127.0.0.1:$port/?terrain=1"
echo "   Lighter three.js page: http://127.0.0.1:$port/three   JSON: http://127.0.0.1:$port/tilesets"
echo
exec "$tinsmith" serve out/red-butte.3dtiles --port "$port" --quiet
