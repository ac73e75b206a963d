#!/usr/bin/env bash
# Side-by-side run on SRTM N44W072 (1.44 M points): the multilevel fitter
# (points projected to UTM 19N) against delatin (greedy-insertion TIN on the
# same grid), for max-error targets given as arguments (default 10 5 2 m),
# then delatin refined to the fitter's vertex counts (RMSE at equal count).
# Errors of both are measured at every DEM point.
#
#   bash tests/bench/fit/srtm_vs_delatin.sh BUILD_DIR/fit_scale_bench [TARGET...]
# Needs gdal-bin (gdal_translate, gdaltransform), node and npm (delatin is
# installed into a scratch directory, not the repository).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bench="$(realpath "$1")"; shift
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(10 5 2)
hgt="$(realpath "$here/../../../../shared/data/srtm/N44W072.hgt")"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
cd "$scratch"
gdal_translate -q -of XYZ "$hgt" ll.xyz
awk '{print $1, $2}' ll.xyz | gdaltransform -s_srs EPSG:4326 -t_srs EPSG:32619 -output_xy > xy.txt
paste -d' ' xy.txt <(awk '{print $3}' ll.xyz) > utm.xyz
echo '{"type":"module"}' > package.json
npm install --silent --no-audit --no-fund delatin@0.2.0 >/dev/null
cp "$here/delatin_srtm.mjs" .
node delatin_srtm.mjs "$hgt" "${targets[@]}"
counts=()
for t in "${targets[@]}"; do
  echo "fit, max error $t m, lambda 0.01 lambda_d, thin-plate:"
  line=$(/usr/bin/time -f "  %e s wall, %U s user, %M KB peak" "$bench" xyz utm.xyz --max-error "$t" --lambda 0.01 2>&1 | tail -2)
  echo "$line"
  counts+=("n$(sed -nE 's/.* vertices ([0-9]+) .*/\1/p' <<<"$line")")
done
echo "delatin at the fitter's vertex counts (RMSE at equal vertex count):"
node delatin_srtm.mjs "$hgt" "${counts[@]}"
