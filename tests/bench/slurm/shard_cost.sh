#!/usr/bin/env bash
# What sharding costs today (issue 24's benchmark, without a cluster): one
# `tinsmith tile` run against the 1 + 4^Z shards `tinsmith slurm` writes,
# each run as its array task would run (one thread), timed by /usr/bin/time —
# per-shard peak memory and the shards' total CPU against the one run's —
# then their merge, checked byte for byte against the one run. Task 0 plans
# (the planning fit, once) and tiles the top down to the shard zoom, but
# over 2^18 vertices not above the mosaic zoom K: the merge builds those
# tiles from the shards' zoom-K tiles, and counts in the total;
# `tinsmith slurm` itself only writes the scripts, and counts too.
#
#   bash tests/bench/slurm/shard_cost.sh TINSMITH TIN TOLERANCE SHARD_ZOOM [WORKDIR]
# e.g. the Red Butte DEM-TIN of tests/bench/tiles/vs_martini.sh (KEEP=DIR keeps it)
# at 1 m, shard zoom 2.
set -euo pipefail
[ $# -ge 4 ] || { echo "usage: shard_cost.sh TINSMITH TIN TOLERANCE SHARD_ZOOM [WORKDIR]" >&2; exit 2; }
tinsmith="$(realpath "$1")"; tin="$(realpath "$2")"; tolerance="$3"; zoom="$4"
work="${5:-$(mktemp -d)}"
mkdir -p "$work"
cd "$work"
rm -rf one.3dtiles merged.3dtiles w times.txt
/usr/bin/time -f "%e %U %S %M" -o one.time "$tinsmith" tile "$tin" --tolerance "$tolerance" \
  --threads 1 -q -o one.3dtiles
/usr/bin/time -f "%e %U %S %M" -o plan.time "$tinsmith" slurm "$tin" --tolerance "$tolerance" \
  --shard-zoom "$zoom" --threads 1 --workdir w -o merged.3dtiles -q >/dev/null
tasks=$(( 1 + (1 << (2 * zoom)) ))
for k in $(seq 0 $((tasks - 1))); do
  SLURM_ARRAY_TASK_ID=$k /usr/bin/time -f "$k %e %U %S %M" -a -o times.txt \
    bash w/shard.sh >"w/logs/shard-$k.log" 2>&1
done
/usr/bin/time -f "%e %U %S %M" -o merge.time bash w/merge.sh >w/logs/merge.log 2>&1
same=$(cmp -s merged.3dtiles one.3dtiles && echo "the same bytes" || echo "DIFFERENT bytes")
read -r ow ou os om <one.time
read -r mw mu ms mm <merge.time
read -r pw pu ps pm <plan.time
awk -v ow="$ow" -v oc="$(echo "$ou $os" | awk '{print $1 + $2}')" -v om="$om" \
    -v mc="$(echo "$mu $ms" | awk '{print $1 + $2}')" -v mm="$mm" -v tasks="$tasks" -v same="$same" \
    -v pc="$(echo "$pu $ps" | awk '{print $1 + $2}')" -v pm="$pm" '
  { c = $3 + $4; cpu += c; if ($5 > peak) peak = $5; if (min == "" || $5 < min) min = $5
    if ($1 > 0 && $5 > subtree) subtree = $5
    if ($1 == 0) { top = c; topm = $5 } }
  END {
    printf "| run | CPU s | peak MB |\n|---|---|---|\n"
    printf "| one tinsmith tile | %.2f | %.0f |\n", oc, om / 1024
    printf "| tinsmith slurm (the scripts) | %.2f | %.0f |\n", pc, pm / 1024
    printf "| %d shards (sum of CPU; largest and smallest peak) | %.2f | %.0f (%.2f×), smallest %.0f |\n", tasks, cpu, peak / 1024, peak / om, min / 1024
    printf "| task 0: the plan and the top (from zoom K when K > 0) | %.2f | %.0f |\n", top, topm / 1024
    printf "| the largest subtree shard | | %.0f (%.2f×) |\n", subtree / 1024, subtree / om
    printf "| merge (over 2^18 vertices: the tiles above K) | %.2f | %.0f |\n", mc, mm / 1024
    printf "| scripts + shards + merge | %.2f (%.2f×) | |\n", pc + cpu + mc, (pc + cpu + mc) / oc
    printf "\nThe merged store and the one run: %s.\n", same
  }' times.txt
