#!/usr/bin/env bash
# tinsmith's Cesium terrain (quantized-mesh-1.0) against the terrain a web
# developer makes with npm @mapbox/martini and a small quantized-mesh encoder,
# on one DEM, in one run (issue 23's benchmark; neither cesium-terrain-builder
# nor mago-3d-terrainer can be built from Debian's or npm's packages). Both
# have the same tiles (tinsmith's layer.json: levels and x/y of the TMS
# EPSG:4326 grid). martini is run three times — at each level's CesiumJS
# error (C), at the error tinsmith's records declare for the level (T), and
# at T scaled by how far martini overshot it there (E) — and all are measured
# the same way, after quantization: every .terrain decoded as a client decodes
# it into the geographic working frame and measured against the geographic
# DEM-TIN by tiles::triangleDifferences (tile_error_bench terrain-error).
#
#   bash tests/bench/tiles/terrain_vs_martini.sh TINSMITH TILE_ERROR_BENCH DEM TOLERANCE
#     DEM: red-butte (../shared/data/red-butte/dem.tif, EPSG:26912) or srtm
#          (../shared/data/srtm/N44W072.hgt projected to UTM 19N, EPSG:32619)
#     TOLERANCE: tinsmith tile --tolerance (m): the finest level is the first
#          whose CesiumJS error is at most it
# Needs gdal-bin, node and npm (martini goes into a scratch directory, not the
# repository), jq, /usr/bin/time. KEEP=DIR keeps the files there;
# MARTINI_SPACING=M the largest spacing of martini's grids in the working
# frame (m; default the DEM's), MARTINI_MIN_CELLS and MARTINI_MAX_CELLS
# (powers of two, default 64, Cesium's 65-sample heightmap tile, and 1024)
# bound a grid's cells a side, MARTINI_FILL=pullpush|nearest how grid
# nodes outside the TIN are filled (tile_error_bench terrain-grids; default
# pullpush); TRIM_HULL as vs_martini.sh; THREADS the measuring threads
# (default 2).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
die() { echo "terrain_vs_martini.sh: $*" >&2; exit 2; }
[ $# -eq 4 ] || die "usage: terrain_vs_martini.sh TINSMITH TILE_ERROR_BENCH red-butte|srtm TOLERANCE"
tinsmith="$(realpath "$1")" || die "no tinsmith binary at $1"
bench="$(realpath "$2")" || die "no tile_error_bench at $2"
dem_name="$3"
tolerance="$4"
[ -x "$tinsmith" ] || die "$tinsmith is not executable"
[ -x "$bench" ] || die "$bench is not executable"
for tool in gdal_translate gdaltransform node npm jq /usr/bin/time; do
  command -v "$tool" >/dev/null || die "$tool is missing (gdal-bin, nodejs, npm, jq, time)"
done
data="$(realpath "$here/../../../../shared/data")"
case "$dem_name" in
  red-butte) dem="$data/red-butte/dem.tif"; crs=EPSG:26912 ;;
  srtm) dem="$data/srtm/N44W072.hgt"; crs=EPSG:32619 ;;
  *) die "DEM must be red-butte or srtm, not '$dem_name'" ;;
esac
[ -f "$dem" ] || die "no DEM at $dem"
threads=${THREADS:-2}

if [ -n "${KEEP:-}" ]; then
  work="$(mkdir -p "$KEEP" && realpath "$KEEP")"
else
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
fi
cd "$work"
echo '{"type":"module","private":true}' > package.json
npm install --silent --no-audit --no-fund @mapbox/martini@0.2.0 >/dev/null ||
  die "npm could not install @mapbox/martini@0.2.0"
cp "$here/martini_terrain.mjs" "$here/terrain_vs_martini_table.mjs" .

# The DEM-TIN, as vs_martini.sh makes it: every valid DEM cell a point in the
# project CRS, the hull trimmed at 3 cells.
gdal_translate -q -of XYZ "$dem" cells.xyz
if [ "$dem_name" = srtm ]; then
  awk '{print $1, $2}' cells.xyz | gdaltransform -s_srs EPSG:4326 -t_srs "$crs" -output_xy > xy.txt
  paste -d' ' xy.txt <(awk '{print $3}' cells.xyz) > projected.xyz
else
  mv cells.xyz projected.xyz
fi
cell=$(awk 'NR == 1 {x = $1; y = $2} NR == 2 {printf "%.6f\n", sqrt(($1 - x)^2 + ($2 - y)^2); exit}' projected.xyz)
spacing="${MARTINI_SPACING:-$cell}"
max_cells="${MARTINI_MAX_CELLS:-1024}"
min_cells="${MARTINI_MIN_CELLS:-64}"
fill="${MARTINI_FILL:-pullpush}"
awk '$3 !~ /nan/ && $3 > -1000' projected.xyz > points.xyz
trim=${TRIM_HULL:-$(awk -v r="$cell" 'BEGIN {printf "%.3f", 3 * r}')}
trim_flag=()
awk -v t="$trim" 'BEGIN {exit !(t > 0)}' && trim_flag=(--trim-hull "$trim")
/usr/bin/time -f '%e %M %U %S' -o tin.time "$tinsmith" tin --points points.xyz --crs "$crs" "${trim_flag[@]}" -o dem.tin -q
echo "DEM $dem_name: $(wc -l < points.xyz) valid cells of $(wc -l < projected.xyz), $crs, hull: ${trim_flag[*]:-not trimmed}; martini grids at most $spacing m apart, $min_cells to $max_cells cells a side, filled by $fill"

# tinsmith's terrain, one thread.
/usr/bin/time -f '%e %M %U %S' -o tile.time \
  "$tinsmith" tile dem.tin --scheme quantized-mesh --tolerance "$tolerance" --threads 1 --json \
  -o dem.3dtiles > tinsmith.json
"$bench" terrain-store dem.3dtiles > tinsmith_store.jsonl
"$bench" terrain-error dem.tin dem.3dtiles "$threads" tinsmith_tiles.jsonl > tinsmith_error.jsonl
cesium=$(jq -r '[.terrain.levels[] | "\(.level):\(.cesiumError)"] | join(",")' tinsmith.json)
declared=$(jq -r '[.terrain.levels[] | "\(.level):\([.maxError, 0.01] | max)"] | join(",")' tinsmith.json)

# martini over the same tiles, one thread (node): the grids, then the runs.
/usr/bin/time -f '%e %M %U %S' -o grids.time \
  "$bench" terrain-grids dem.tin dem.3dtiles "$spacing" "$min_cells:$max_cells" dem.grids "$fill" > grids.json
martini_run() {  # NAME TOLERANCES
  rm -rf "martini_$1"
  /usr/bin/time -f '%e %M %U %S' -o "martini_$1.time" \
    node martini_terrain.mjs dem.grids "$2" "martini_$1" > "martini_$1.jsonl"
  "$bench" terrain-error dem.tin "martini_$1" "$threads" "martini_$1_tiles.jsonl" > "martini_$1_error.jsonl"
}
martini_run cesium "$cesium"
martini_run declared "$declared"
# E: T's tolerance times min(1, T / what T measured), per level.
equalised=$(node -e '
  const fs = require("fs");
  const rows = (f) => fs.readFileSync(f, "utf8").trim().split("\n").map(JSON.parse).filter((r) => r.level !== undefined);
  const measured = new Map(rows("martini_declared_error.jsonl").map((r) => [r.level, r.maxError]));
  console.log(rows("martini_declared.jsonl").map((r) =>
    `${r.level}:${Math.max(0.01, r.tolerance * Math.min(1, r.tolerance / Math.max(measured.get(r.level), 1e-6)))}`).join(","));')
martini_run equalised "$equalised"

echo "commit $(git -C "$here" describe --always --dirty), $(uptime | sed 's/.*load average/load average/')"
echo "tinsmith tile $dem_name.tin --scheme quantized-mesh --tolerance $tolerance --threads 1"
node terrain_vs_martini_table.mjs .
