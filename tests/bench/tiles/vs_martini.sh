#!/usr/bin/env bash
# tinsmith's tile pyramid against the one a web developer makes with npm
# @mapbox/martini + draco3d, on one DEM, in one run (issue 11, "Speed, size and
# fidelity"). Both pyramids have the same zooms and tile squares (tinsmith's),
# each martini tile is meshed at its zoom's tolerance, and both are measured
# the same way: the exact max vertical difference against the DEM-TIN (every
# valid DEM cell a point), by tiles::maxVerticalDifference.
#
#   bash tests/bench/tiles/vs_martini.sh TINSMITH TILE_ERROR_BENCH DEM TOLERANCE
#     DEM: red-butte (../shared/data/red-butte/dem.tif, EPSG:26912) or srtm
#          (../shared/data/srtm/N44W072.hgt projected to UTM 19N, EPSG:32619)
#     TOLERANCE: tinsmith's finest tolerance (m)
# Needs gdal-bin, node and npm (martini and draco3d go into a scratch
# directory, not the repository), jq, /usr/bin/time. KEEP=DIR keeps the files
# there; MARTINI_SPACING=M sets the largest spacing of martini's grids (m;
# default the DEM's), MARTINI_GRID=N (2^k + 1) one grid size for every tile;
# TRIM_HULL=M trims the DEM-TIN's hull slivers (tinsmith tin --trim-hull M;
# default 3 cells: a DEM with nodata or a projected DEM is not convex, and its
# hull's slivers are walls no tiler should follow; 0 keeps them).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
die() { echo "vs_martini.sh: $*" >&2; exit 2; }
[ $# -eq 4 ] || die "usage: vs_martini.sh TINSMITH TILE_ERROR_BENCH red-butte|srtm TOLERANCE"
tinsmith="$(realpath "$1")" || die "no tinsmith binary at $1"
bench="$(realpath "$2")" || die "no tile_error_bench at $2 (cmake --build build/release --target tile_error_bench)"
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

if [ -n "${KEEP:-}" ]; then
  work="$(mkdir -p "$KEEP" && realpath "$KEEP")"
else
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
fi
cd "$work"
echo '{"type":"module","private":true}' > package.json
npm install --silent --no-audit --no-fund @mapbox/martini@0.2.0 draco3d@1.5.5 >/dev/null ||
  die "npm could not install @mapbox/martini@0.2.0 and draco3d@1.5.5"
cp "$here/martini_tiles.mjs" "$here/vs_martini_table.mjs" .

# The DEM-TIN: every valid DEM cell a point in the project CRS.
gdal_translate -q -of XYZ "$dem" cells.xyz
if [ "$dem_name" = srtm ]; then
  awk '{print $1, $2}' cells.xyz | gdaltransform -s_srs EPSG:4326 -t_srs "$crs" -output_xy > xy.txt
  paste -d' ' xy.txt <(awk '{print $3}' cells.xyz) > projected.xyz
else
  mv cells.xyz projected.xyz
fi
# The DEM's spacing: the first two cells of a row (x east); martini's grids are
# at least this fine (MARTINI_SPACING=M overrides it).
resolution=$(awk 'NR == 1 {x = $1; y = $2} NR == 2 {printf "%.6f\n", sqrt(($1 - x)^2 + ($2 - y)^2); exit}' projected.xyz)
resolution="${MARTINI_SPACING:-$resolution}"
[ -n "${MARTINI_GRID:-}" ] && resolution="n=$MARTINI_GRID"
awk '$3 !~ /nan/ && $3 > -1000' projected.xyz > points.xyz
echo "DEM $dem_name: $(wc -l < points.xyz) valid cells of $(wc -l < projected.xyz), $crs; martini grids: $resolution (m apart at most, or n= nodes a side)"
trim=${TRIM_HULL:-$(awk -v r="$(awk 'NR == 1 {x = $1; y = $2} NR == 2 {printf "%.6f", sqrt(($1 - x)^2 + ($2 - y)^2); exit}' projected.xyz)" 'BEGIN {printf "%.3f", 3 * r}')}
trim_flag=()
awk -v t="$trim" 'BEGIN {exit !(t > 0)}' && trim_flag=(--trim-hull "$trim")
/usr/bin/time -f '%e %M %U %S' -o tin.time "$tinsmith" tin --points points.xyz --crs "$crs" "${trim_flag[@]}" -o dem.tin -q
echo "hull: ${trim_flag[*]:-not trimmed}"
echo "tinsmith tin: $(cut -d' ' -f1 tin.time) s, $(( $(cut -d' ' -f2 tin.time) / 1024 )) MB peak"

# tinsmith's pyramid, one thread.
/usr/bin/time -f '%e %M %U %S' -o tile.time \
  "$tinsmith" tile dem.tin -o dem.3dtiles --tolerance "$tolerance" --json --threads 1 > tinsmith.json
"$bench" store dem.3dtiles > tinsmith_store.jsonl
tolerances=$(jq -r '[.zooms[] | "\(.zoom):\(.tolerance)"] | join(",")' tinsmith.json)

# martini's pyramid over the same tile squares, one thread (node).
/usr/bin/time -f '%e %M %U %S' -o grids.time \
  "$bench" grids dem.tin dem.3dtiles "$resolution" "$tolerances" dem.grids > grids.json
/usr/bin/time -f '%e %M %U %S' -o martini.time node martini_tiles.mjs dem.grids martini.meshes > martini.jsonl
"$bench" error dem.tin martini.meshes 2 > martini_error.jsonl

echo "commit $(git -C "$here" describe --always --dirty), $(uptime | sed 's/.*load average/load average/')"
echo "tinsmith tile $dem_name.tin --tolerance $tolerance --threads 1"
node vs_martini_table.mjs tinsmith.json tinsmith_store.jsonl tile.time grids.json grids.time \
  martini.jsonl martini.time martini_error.jsonl
