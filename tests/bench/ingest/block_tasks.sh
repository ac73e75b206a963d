#!/usr/bin/env bash
# What each block task of `tinsmith slurm-tin` costs, as the cluster runs
# them (issue 24's per-shard goal for the ingest), for one or more tinsmith
# binaries side by side: the blocks prepared once (slurm-tin without
# --submit, by the first binary), then every block task one after another
# under /usr/bin/time, binary by binary, each binary's triangles kept apart
# and compared byte for byte with the first's; then the assembly.
#
#   bash tests/bench/ingest/block_tasks.sh POINTS.xyz CRS BLOCK_POINTS RADIUS WORKDIR TINSMITH...
# e.g. (the points: tests/bench/ingest/block_tin.sh's header)
#   bash tests/bench/ingest/block_tasks.sh random12m.xyz EPSG:32619 200000 40 /tmp/bt old/tinsmith build/release/bin/tinsmith
set -euo pipefail
[ $# -ge 6 ] || { echo "usage: block_tasks.sh POINTS CRS BLOCK_POINTS RADIUS WORKDIR TINSMITH..." >&2; exit 2; }
points="$(realpath "$1")"; crs="$2"; block_points="$3"; radius="$4"; work="$5"; shift 5
binaries=()
for b in "$@"; do binaries+=("$(realpath "$b")"); done
mkdir -p "$work"
cd "$work"
rm -rf blocks tris-* times-* ./*.tin
/usr/bin/time -f "%e %U %S %M" -o prepare.time "${binaries[0]}" slurm-tin --points "$points" \
  --crs "$crs" --block-points "$block_points" --max-circumradius "$radius" --workdir blocks \
  -o out.tin --json >prepare.json
tasks=$(python3 -c 'import json, sys; print(len(json.load(open(sys.argv[1]))["tasks"]))' prepare.json)
echo "| binary | block tasks | CPU s (sum) | largest task MiB | smallest MiB | assembly CPU s / MiB | triangles = first binary's |"
echo "|---|---|---|---|---|---|---|"
for i in "${!binaries[@]}"; do
  bin="${binaries[$i]}"
  rm -rf blocks/triangles && mkdir blocks/triangles
  for k in $(seq 0 $((tasks - 1))); do
    /usr/bin/time -f "%e %U %S %M" -a -o "times-$i" "$bin" tin --blocks blocks --block "$k" \
      --threads 1 -q >/dev/null
  done
  /usr/bin/time -f "%e %U %S %M" -o "assemble-$i.time" "$bin" tin --blocks blocks -o "out-$i.tin" -q
  cp -r blocks/triangles "tris-$i"
  same="yes"
  if [ "$i" -gt 0 ]; then
    diff -rq tris-0 "tris-$i" >/dev/null && cmp -s out-0.tin "out-$i.tin" || same="NO"
  fi
  read -r _ au as am <"assemble-$i.time"
  awk -v bin="$bin" -v tasks="$tasks" -v same="$same" -v ac="$(echo "$au $as" | awk '{print $1 + $2}')" -v am="$am" '
    { cpu += $2 + $3; if ($4 > peak) peak = $4; if (min == "" || $4 < min) min = $4 }
    END { printf "| %s | %d | %.2f | %.1f | %.1f | %.2f / %.0f | %s |\n", bin, tasks, cpu, peak / 1024, min / 1024, ac, am / 1024, same }' "times-$i"
done
read -r pw pu ps pm <prepare.time
echo
echo "Preparation (first binary): $pw s wall, $(echo "$pu $ps" | awk '{print $1 + $2}') s CPU, $((pm / 1024)) MiB."
