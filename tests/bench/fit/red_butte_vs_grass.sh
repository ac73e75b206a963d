#!/usr/bin/env bash
# tinsmith fit against GRASS GIS v.surf.rst on Red Butte (EPSG:26912), side by
# side in one run, on the same input points:
#   (a) 7 000 random valid DEM cells (cell centres; Python random, seed 2026),
#   (b) every vertex of the 20 m contours (contours.gpkg, z = attribute elev).
# Each surface is sampled at the centre of every valid DEM cell and compared
# with the DEM by one evaluator (RMSE, max |error|).
#
#   bash tools/setup.sh --bench      # grass-core, python3-gdal, python3-numpy
#   bash tests/bench/fit/red_butte_vs_grass.sh BUILD_DIR/bin/tinsmith [RUNS]
#
# KEEP_SCRATCH=1 keeps the working folder (inputs, surfaces, logs).
# RUNS (default 3): every timed step runs RUNS times; the medians of its wall
# time and of its CPU time (user + system, bash `time`) are reported (repeated
# runs give the same surface; the last is evaluated). On a machine shared
# with other jobs the wall times vary; the CPU times much less.
# What the times include:
#   v.surf.rst  the v.surf.rst command alone, inside a running GRASS session:
#               reading the imported points from the GRASS database,
#               interpolating on the DEM's grid (g.region raster=dem) and
#               writing the elevation raster. Not timed: GRASS start-up,
#               v.in.ascii (import), r.out.gdal (export).
#   tinsmith    the whole `tinsmith fit` process: reading the XYZ text,
#               fitting, writing the .tin; "fitting": the fitting alone
#               ("seconds" of --stats). Not timed: the choice of lambda (below)
#               and `tinsmith query` (sampling the .tin at the DEM cells).
# Threads: both tools run with 1 thread (v.surf.rst nprocs=1 is its default)
# and with 2 (tinsmith's default is all cores); the speed ratio compares
# equal thread counts.
#
# v.surf.rst keeps all its defaults (tension 40, smooth 0.5, segmax 40,
# npmin 300, dmin and dmax from the cell size), as for the figures in
# ../shared/data/README.md.
set -euo pipefail

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $0 BUILD_DIR/bin/tinsmith [RUNS]" >&2
  exit 2
fi
tinsmith="$(realpath "$1")"
runs="${2:-3}"
here="$(cd "$(dirname "$0")" && pwd)"
data="$(realpath "$here/../../../../shared/data/red-butte")"
# Debian's python3: it has python3-gdal and python3-numpy (a python3 that
# comes earlier in PATH may not).
py=/usr/bin/python3

# tinsmith fit: refine every cell that holds input points (count:0) down to
# level 9, the first grid whose cells (about 13.7 m here) are finer than the
# 26.5 m grid the inputs were sampled from; thin-plate smoothing (default).
# Two lambdas: the default (lambda_d), and the one of LAMBDAS with the
# smallest 5-fold cross-validation RMSE at held-out input points (seed 1).
# Neither choice looks at the DEM.
FIT=(--criterion count:0 --max-level 9)
LAMBDAS=(1 0.3 0.1 0.03 0.01)

[ -x "$tinsmith" ] || { echo "not an executable: $tinsmith" >&2; exit 2; }
command -v grass >/dev/null || { echo "GRASS GIS is missing: bash tools/setup.sh --bench" >&2; exit 2; }
"$py" -c 'import numpy; from osgeo import gdal, ogr' 2>/dev/null ||
  { echo "$py lacks GDAL or NumPy: bash tools/setup.sh --bench" >&2; exit 2; }
case "$runs" in '' | *[!0-9]* | 0) echo "RUNS must be a whole number >= 1" >&2; exit 2 ;; esac

scratch="$(mktemp -d)"
if [ -n "${KEEP_SCRATCH:-}" ]; then
  echo "scratch (kept): $scratch"
else
  trap 'rm -rf "$scratch"' EXIT
fi
cd "$scratch"

# ---------------------------------------------------------------- inputs
# cells.xy: every valid DEM cell centre, row-major (where the surfaces are
# evaluated); random7000.xyz and contours.xyz: what both tools get.
"$py" - "$data" <<'PY'
import random, sys
import numpy as np
from osgeo import gdal, ogr
gdal.UseExceptions(); ogr.UseExceptions()
data = sys.argv[1]
dem = gdal.Open(f"{data}/dem.tif")
x0, dx, _, y0, _, dy = dem.GetGeoTransform()
z = dem.GetRasterBand(1).ReadAsArray().astype(np.float64)
rows, cols = np.nonzero(np.isfinite(z))          # row-major order
xs, ys = x0 + (cols + 0.5) * dx, y0 + (rows + 0.5) * dy
with open("cells.xy", "w") as f:
    f.writelines(f"{x:.4f} {y:.4f}\n" for x, y in zip(xs, ys))
pick = sorted(random.Random(2026).sample(range(len(xs)), 7000))
with open("random7000.xyz", "w") as f:
    f.writelines(f"{xs[i]:.4f} {ys[i]:.4f} {z[rows[i], cols[i]]!r}\n" for i in pick)
source = ogr.Open(f"{data}/contours.gpkg")      # must outlive the layer
layer = source.GetLayerByName("contours")
n = 0
with open("contours.xyz", "w") as f:
    for feature in layer:
        elev = feature.GetField("elev")
        for x, y, *_ in feature.GetGeometryRef().GetPoints():
            f.write(f"{x!r} {y!r} {elev!r}\n")
            n += 1
print(f"DEM {dem.RasterXSize} x {dem.RasterYSize} cells, {len(xs)} valid; "
      f"inputs: 7000 random valid cells, {n} contour vertices ({layer.GetFeatureCount()} lines)")
PY

# One line per timed configuration (tab-separated): input, tool, threads,
# settings, the file of times (bash `time`: "wall user sys" a line), stats
# file, surface file.
: >results.tsv

# ---------------------------------------------------------------- GRASS
cat >grass_side.sh <<'SH'
set -euo pipefail
TIMEFORMAT='%3R %3U %3S'
r.external -o --quiet input="$DEM" output=dem
g.region --quiet raster=dem
for input in random7000 contours; do
  v.in.ascii --quiet -z -t input="$input.xyz" output="$input" separator=space x=1 y=2 z=3
  for nprocs in 1 2; do
    out="grass_${input}_np$nprocs"
    for ((run = 1; run <= RUNS; run++)); do
      { time v.surf.rst --quiet --overwrite input="$input" elevation="$out" nprocs="$nprocs" 2>>v.surf.rst.log; } 2>>"$out.times"
    done
    r.out.gdal --quiet -c input="$out" output="$out.tif" format=GTiff type=Float64
    printf '%s\tv.surf.rst\t%s\tdefaults\t%s\t-\t%s\n' "$input" "$nprocs" "$out.times" "$out.tif" >>results.tsv
  done
done
SH
echo "GRASS v.surf.rst (defaults), nprocs 1 and 2, $runs runs each ..."
DEM="$data/dem.tif" RUNS="$runs" grass --tmp-location EPSG:26912 --exec bash grass_side.sh 2>grass.log ||
  { cat grass.log >&2; exit 1; }

# ---------------------------------------------------------------- tinsmith
TIMEFORMAT='%3R %3U %3S'
echo "tinsmith fit: lambda by 5-fold cross-validation over the input points ..."
declare -A cv_lambda
for input in random7000 contours; do
  "$py" - "$tinsmith" "$input.xyz" "${LAMBDAS[*]}" "${FIT[@]}" >"cv_$input.txt" <<'PY'
import math, random, subprocess, sys
tinsmith, points, lambdas, fit = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4:]
lines = open(points).readlines()
order = list(range(len(lines)))
random.Random(1).shuffle(order)
folds, best = 5, None
for lam in lambdas:
    sq, n = 0.0, 0
    for k in range(folds):
        held = sorted(order[k::folds])
        held_set = set(held)
        with open("cv_train.xyz", "w") as f:
            f.writelines(l for i, l in enumerate(lines) if i not in held_set)
        with open("cv_test.xy", "w") as f:
            f.writelines(lines[i] for i in held)
        subprocess.run([tinsmith, "fit", "cv_train.xyz", *fit, "--lambda", lam, "-q", "-o", "cv.tin"],
                       check=True, stderr=subprocess.DEVNULL)
        out = subprocess.run([tinsmith, "query", "cv.tin", "--points", "cv_test.xy"],
                             check=True, capture_output=True, text=True).stdout.splitlines()
        for i, line in zip(held, out):
            f = line.split()
            if f[2] != "outside":
                sq += (float(f[3]) - float(lines[i].split()[2])) ** 2
                n += 1
    rmse = math.sqrt(sq / n)
    print(f"  {points}: lambda {lam} lambda_d: cross-validation RMSE {rmse:.3f} m ({n} held-out points)")
    if best is None or rmse < best[1]:
        best = (lam, rmse)
print(best[0])
PY
  cv_lambda[$input]=$(tail -1 "cv_$input.txt")
  sed '$d' "cv_$input.txt"
done

echo "tinsmith fit, threads 1 and 2, $runs runs each ..."
for input in random7000 contours; do
  lambdas=(1)
  [ "${cv_lambda[$input]}" != 1 ] && lambdas+=("${cv_lambda[$input]}")
  for lambda in "${lambdas[@]}"; do
    choice="default lambda"
    [ "$lambda" != 1 ] && choice="lambda by cross-validation"
    for threads in 1 2; do
      out="tinsmith_${input}_l${lambda}_t$threads"
      for ((run = 1; run <= runs; run++)); do
        { time "$tinsmith" fit "$input.xyz" "${FIT[@]}" --lambda "$lambda" --threads "$threads" --crs EPSG:26912 -q \
          -o "$out.tin" --stats "$out.json" 2>>tinsmith.log; } 2>>"$out.times"
      done
      "$tinsmith" query "$out.tin" --points cells.xy >"$out.query"
      printf '%s\ttinsmith\t%s\t%s\t%s\t%s\t%s\n' "$input" "$threads" \
        "\`${FIT[*]} --lambda $lambda\` ($choice)" "$out.times" "$out.json" "$out.query" >>results.tsv
    done
  done
done

# ---------------------------------------------------------------- evaluation
"$py" - "$data/dem.tif" <<'PY'
import json, sys
import numpy as np
from osgeo import gdal
gdal.UseExceptions()
dem = gdal.Open(sys.argv[1])
ref = dem.GetRasterBand(1).ReadAsArray().astype(np.float64)
valid = np.isfinite(ref)

def grass_surface(path):
    """The v.surf.rst raster; it must be on the DEM's grid."""
    r = gdal.Open(path)
    if (r.RasterXSize, r.RasterYSize) != (dem.RasterXSize, dem.RasterYSize) or \
            not np.allclose(r.GetGeoTransform(), dem.GetGeoTransform(), rtol=0, atol=1e-6):
        sys.exit(f"{path} is not on the DEM grid")
    b = r.GetRasterBand(1)
    a = b.ReadAsArray().astype(np.float64)
    if b.GetNoDataValue() is not None:
        a[a == b.GetNoDataValue()] = np.nan
    return a

def tinsmith_surface(path):
    """`tinsmith query --points cells.xy`: one line per valid DEM cell in
    row-major order, "x y z Z normal ..." or "x y outside"."""
    values = []
    for line in open(path):
        f = line.split()
        values.append(np.nan if f[2] == "outside" else float(f[3]))
    if len(values) != valid.sum():
        sys.exit(f"{path}: {len(values)} samples for {valid.sum()} cells")
    a = np.full(ref.shape, np.nan)
    a[valid] = values
    return a

runs = []
for line in open("results.tsv"):
    input_, tool, threads, settings, times, stats, surface = line.rstrip("\n").split("\t")
    stats = json.load(open(stats)) if tool == "tinsmith" else None
    wall_user_sys = np.loadtxt(times, ndmin=2)
    runs.append(dict(input=input_, tool=tool, threads=int(threads), settings=settings,
                     seconds=np.median(wall_user_sys[:, 0]), cpu=np.median(wall_user_sys[:, 1] + wall_user_sys[:, 2]),
                     stats=stats,
                     surface=grass_surface(surface) if tool == "v.surf.rst" else tinsmith_surface(surface)))

names = {"random7000": "7 000 random DEM cells", "contours": "20 m contours"}
print()
print("| input | tool, settings | threads | RMSE | max error | time: wall (CPU) | speed vs v.surf.rst, same threads: wall (CPU) |")
print("|---|---|---|---|---|---|---|")
notes = []
for input_, name in names.items():
    group = [r for r in runs if r["input"] == input_]
    # The cells where every surface of this input is defined (v.surf.rst
    # extrapolates over the whole region, the tinsmith TIN does not).
    common = valid.copy()
    for r in group:
        common &= np.isfinite(r["surface"])
    grass = [r for r in group if r["tool"] == "v.surf.rst"]
    same = all(np.array_equal(g["surface"], grass[0]["surface"], equal_nan=True) for g in grass)
    note = f"{name}: v.surf.rst nprocs=1 and 2 give {'the same surface' if same else 'different surfaces'}."
    if common.sum() < valid.sum():
        full = grass[0]["surface"][valid] - ref[valid]
        out = valid.sum() - common.sum()
        note += (f" {out} of the {valid.sum()} valid DEM cells {'lies' if out == 1 else 'lie'} outside the tinsmith TIN "
                 f"(it ends at the square over the input's bounding box); the errors are over the other "
                 f"{common.sum()}. Over all {valid.sum()}, v.surf.rst (nprocs=1) has RMSE "
                 f"{np.sqrt(np.mean(full ** 2)):.3f} m, max error {np.abs(full).max():.2f} m.")
    notes.append(note)
    grass_time = {r["threads"]: r for r in group if r["tool"] == "v.surf.rst"}
    for r in group:
        err = r["surface"][common] - ref[common]
        rmse, emax = np.sqrt(np.mean(err ** 2)), np.abs(err).max()
        if r["tool"] == "v.surf.rst":
            tool = "GRASS `v.surf.rst`, defaults"
            time = f"{r['seconds']:.2f} s ({r['cpu']:.2f} s)"
            ratio = "reference"
        else:
            tool = f"tinsmith fit {r['settings']}, {r['stats']['final']['vertices']} vertices"
            time = f"{r['seconds']:.2f} s ({r['cpu']:.2f} s); fitting {r['stats']['seconds']:.2f} s"
            g = grass_time[r["threads"]]
            ratio = f"{g['seconds'] / r['seconds']:.0f}× ({g['cpu'] / r['cpu']:.0f}×)"
        print(f"| {name} | {tool} | {r['threads']} | {rmse:.3f} m | {emax:.2f} m | {time} | {ratio} |")
print()
for n in notes:
    print(f"- {n}")
PY
