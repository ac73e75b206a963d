#!/usr/bin/env bash
# What building a TIN block by block costs (issue 24's ingest that scales):
# `tinsmith tin` on all the points at once against `tinsmith tin
# --block-points N` for a few N, side by side in one run, each timed by
# /usr/bin/time (wall, CPU, peak memory). Both with the same CRS; the one run
# trims the hull's slivers with --trim-hull (and once more without: the mesh
# written as built, no copy), the blocks leave them out by --max-circumradius
# (the two differ only there). The ratios are against the trimmed run.
#
#   bash tests/bench/ingest/block_tin.sh TINSMITH POINTS.xyz CRS TRIM_HULL RADIUS "N1 N2 ..." [WORKDIR]
# e.g. the SRTM N44W072 points of tests/slurm/srtm_shards_test.sh:
#   bash tests/bench/ingest/block_tin.sh build/release/bin/tinsmith srtm.xyz EPSG:32619 300 150 "100000 400000"
# or 12 M random points over 30 km × 30 km of a smooth terrain (Debian's
# mawk; another awk draws other points):
#   awk 'BEGIN { srand(24); for (i = 0; i < 12000000; i++) { x = 500000 + 30000 * rand();
#     y = 4900000 + 30000 * rand(); printf "%.3f %.3f %.3f\n", x, y,
#     300 + 80 * sin(x / 3100) * cos(y / 2700) + 0.02 * (x - 500000) / 30 } }' > random12m.xyz
#   bash tests/bench/ingest/block_tin.sh build/release/bin/tinsmith random12m.xyz EPSG:32619 100 40 "200000"
set -euo pipefail
[ $# -ge 6 ] || { echo "usage: block_tin.sh TINSMITH POINTS CRS TRIM_HULL RADIUS \"N...\" [WORKDIR]" >&2; exit 2; }
tinsmith="$(realpath "$1")"; points="$(realpath "$2")"; crs="$3"; trim="$4"; radius="$5"; sizes="$6"
work="${7:-$(mktemp -d)}"
mkdir -p "$work"
cd "$work"
rm -f times.txt
/usr/bin/time -f "one-run %e %U %S %M" -a -o times.txt "$tinsmith" tin --points "$points" --crs "$crs" \
  --trim-hull "$trim" -q -o one.tin
/usr/bin/time -f "untrimmed %e %U %S %M" -a -o times.txt "$tinsmith" tin --points "$points" \
  --crs "$crs" -q -o untrimmed.tin
for n in $sizes; do
  /usr/bin/time -f "blocks-$n %e %U %S %M" -a -o times.txt "$tinsmith" tin --points "$points" \
    --crs "$crs" --block-points "$n" --max-circumradius "$radius" --report "blocks-$n.json" -q \
    -o "blocks-$n.tin"
done
one_v=$("$tinsmith" info one.tin --json | python3 -c 'import json, sys; j = json.load(sys.stdin); print(j["vertices"], j["triangles"])')
echo "| run | blocks | largest block (points triangulated) | vertices | triangles | wall s | CPU s | peak MB | peak ÷ one run |"
echo "|---|---|---|---|---|---|---|---|---|"
while read -r name wall user sys kb; do
  if [ "$name" = one-run ]; then
    one_kb=$kb
    echo "| tinsmith tin --trim-hull $trim (all at once) | 1 | - | ${one_v% *} | ${one_v#* } | $wall | $(echo "$user $sys" | awk '{printf "%.2f", $1 + $2}') | $((kb / 1024)) | 1.00 |"
  elif [ "$name" = untrimmed ]; then
    echo "| tinsmith tin (all at once, untrimmed: the mesh written as built) | 1 | - | | | $wall | $(echo "$user $sys" | awk '{printf "%.2f", $1 + $2}') | $((kb / 1024)) | $(awk -v a="$kb" -v b="$one_kb" 'BEGIN { printf "%.2f", a / b }') |"
  else
    n=${name#blocks-}
    python3 - "$n" "$wall" "$user" "$sys" "$kb" "$one_kb" <<'EOF'
import json, sys
n, wall, user, sys_, kb, one = sys.argv[1:]
j = json.load(open(f"blocks-{n}.json"))
b = j["blocks"]
print(f"| --block-points {n} | {b['withPoints']} | {b['largestTriangulated']} | {j['vertices']} | "
      f"{j['triangles']} | {wall} | {float(user) + float(sys_):.2f} | {int(kb) // 1024} | {int(kb) / int(one):.2f} |")
EOF
  fi
done <times.txt
