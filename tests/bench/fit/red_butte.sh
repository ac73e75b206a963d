#!/usr/bin/env bash
# The fitter on Red Butte (EPSG:26912): (a) 7 000 random DEM cells (seed 2026)
# and (b) the vertices of the 20 m contours as input; error (max, RMSE) over
# every valid DEM cell. Reference figures (GRASS v.surf.rst, measured earlier
# on this kind of machine, ../shared/data/README.md): (a) RMSE 3.08 m in 5.7 s,
# (b) RMSE 1.31 m in 19 s.
#
#   bash tests/bench/fit/red_butte.sh BUILD_DIR/fit_scale_bench
# Needs gdal-bin (gdal_translate, ogr2ogr) and python3.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bench="$(realpath "$1")"
data="$(realpath "$here/../../../../shared/data/red-butte")"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
cd "$scratch"
gdal_translate -q -of XYZ "$data/dem.tif" all.xyz
ogr2ogr -f CSV contours.csv "$data/contours.gpkg" -lco GEOMETRY=AS_WKT
python3 - <<'PY'
import csv, math, random, re
cells = [l for l in open('all.xyz') if math.isfinite(float(l.split()[2]))]
open('ref.xyz', 'w').writelines(cells)
random.seed(2026)
open('random7000.xyz', 'w').writelines(random.sample(cells, 7000))
csv.field_size_limit(10**9)
with open('contours.csv') as f, open('contours.xyz', 'w') as o:
    for row in csv.DictReader(f):
        for x, y in re.findall(r'(-?[\d.]+) (-?[\d.]+)', row['WKT']):
            o.write(f"{x} {y} {row['elev']}\n")
PY
for input in random7000 contours; do
  for lambda in 1 0.1; do
    echo "$input.xyz, count > 0, max level 9, lambda $lambda lambda_d, thin-plate:"
    /usr/bin/time -f "  %e s wall, %U s user" "$bench" xyz "$input.xyz" --count-only 0 --max-level 9 --lambda "$lambda" \
      --check ref.xyz | tail -2
  done
done
