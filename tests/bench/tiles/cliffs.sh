#!/usr/bin/env bash
# Steep terrain (issue 21, item 1): the tiler's time per TIN vertex and peak
# memory on a mesa with 600 m walls (cliffs.py), against the same tiler on
# SRTM N44W072 (1.44 M points, tin --trim-hull 300) in the same run, and
# against `tinsmith tin` on the same data. One thread for the tiler. Prints a
# Markdown table; each case is one run (these machines are noisy: the ratios
# are what to read).
#
#   bash tests/bench/tiles/cliffs.sh TINSMITH [WALL ...]     (default walls: 10 1)
# Needs python3, gdal-bin (for SRTM), jq, bc, /usr/bin/time. KEEP=DIR keeps the files.
# SRTM=0 skips the SRTM reference (it takes a minute to prepare).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
die() { echo "cliffs.sh: $*" >&2; exit 2; }
[ $# -ge 1 ] || die "usage: cliffs.sh TINSMITH [WALL ...]"
tinsmith="$(realpath "$1")" || die "no tinsmith binary at $1"
shift
walls=("$@")
[ ${#walls[@]} -gt 0 ] || walls=(10 1)
for tool in python3 jq bc /usr/bin/time; do command -v "$tool" >/dev/null || die "$tool is missing"; done
if [ -n "${KEEP:-}" ]; then
  work="$(mkdir -p "$KEEP" && realpath "$KEEP")"
else
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
fi

# measure NAME COMMAND...: runs it under /usr/bin/time; NAME.time holds
# "seconds peak-KiB".
measure() {
  local name="$1"
  shift
  /usr/bin/time -f '%e %M' -o "$work/$name.time" "$@"
}
seconds() { cut -d' ' -f1 "$work/$1.time"; }
peak_mb() { echo $(( $(cut -d' ' -f2 "$work/$1.time") / 1024 )); }

echo "| case | TIN vertices | tin s / MB | tile tolerance | tile s / MB (1 thread) | µs per vertex | memory ÷ tin's | tiles, zooms | every zoom within |"
echo "|---|---|---|---|---|---|---|---|---|"

# row NAME TOLERANCE: tiles NAME.tin and prints the table row.
row() {
  local name="$1" tolerance="$2" vertices
  vertices=$("$tinsmith" info "$work/$name.tin" --json | jq .vertices)
  measure "$name-tile-$tolerance" "$tinsmith" tile "$work/$name.tin" -o "$work/$name-$tolerance.3dtiles" \
    --tolerance "$tolerance" --threads 1 --json >"$work/$name-$tolerance.json" 2>/dev/null
  local t m
  t=$(seconds "$name-tile-$tolerance")
  m=$(peak_mb "$name-tile-$tolerance")
  printf '| %s | %s | %s / %s | %s m | %s / %s | %.0f | %.1f× | %s, %s | %s |\n' \
    "$name" "$vertices" "$(seconds "$name-tin")" "$(peak_mb "$name-tin")" "$tolerance" "$t" "$m" \
    "$(echo "$t * 1000000 / $vertices" | bc -l)" "$(echo "$m / $(peak_mb "$name-tin")" | bc -l)" \
    "$(jq .tiles "$work/$name-$tolerance.json")" "$(jq '.zooms | length' "$work/$name-$tolerance.json")" \
    "$(jq .withinTolerance "$work/$name-$tolerance.json")"
}

if [ "${SRTM:-1}" != 0 ]; then
  hgt="$(realpath "$here/../../../../shared/data/srtm/N44W072.hgt")" || die "no SRTM tile"
  command -v gdaltransform >/dev/null || die "gdal-bin is missing"
  gdal_translate -q -of XYZ "$hgt" "$work/cells.xyz"  # every cell a point, projected as vs_martini.sh does
  awk '{print $1, $2}' "$work/cells.xyz" | gdaltransform -s_srs EPSG:4326 -t_srs EPSG:32619 -output_xy >"$work/xy.txt"
  paste -d' ' "$work/xy.txt" <(awk '{print $3}' "$work/cells.xyz") | awk '$3 !~ /nan/ && $3 > -1000' >"$work/srtm.xyz"
  measure srtm-tin "$tinsmith" tin --points "$work/srtm.xyz" --crs EPSG:32619 --trim-hull 300 \
    -o "$work/srtm.tin" -q
  row srtm 10
fi

for wall in "${walls[@]}"; do
  name="mesa-wall-${wall}m"
  mkdir -p "$work/$name"
  python3 "$here/cliffs.py" "$work/$name" "$wall"
  measure "$name-tin" "$tinsmith" tin --points "$work/$name/spots.xyz" \
    --breaklines "$work/$name/contours.geojson" --crs EPSG:32612 -o "$work/$name.tin" -q
  for tolerance in 10 2; do row "$name" "$tolerance"; done
done
