#!/usr/bin/env bash
# ctest Slurm.SrtmSixteenShards (issue 24): a real DEM, SRTM N44W072 (the
# 3″ tile of ../shared/data/srtm, 1.44 M cells projected to UTM 19N), tiled
# at 10 m as 16 shards on a real one-node Slurm cluster (local_cluster.sh):
# the merged store holds the bytes of one `tinsmith tile` run, and a shard
# that fails is retried with --resume, after which the merge runs.
#
#   bash tests/slurm/srtm_shards_test.sh TINSMITH HGT WORKDIR      (as root)
#
# The cluster first (WORKDIR/cluster), then the TIN (every cell a point,
# projected by gdaltransform, hull trimmed at 300 m) and the single run
# (one.3dtiles, every core). Then `tinsmith slurm --shard-zoom 2 --submit
# --json --sbatch-args=--hold`: the top and the 16 subtrees as an array, the
# merge after them, both on hold; one subtree's store path is taken by a
# folder holding a foreign file (tinsmith will not replace it) and the jobs
# released. That task alone FAILS, the merge is CANCELLED and writes
# nothing, the 16 other shards are kept. The folder removed, `--resume
# --submit` runs that task again and a new merge, whose store is the single
# run's, byte for byte. The waits are bounded by 420 s in all; everything
# stays in WORKDIR. Ends with `N passed, M failed`; exits 1 on any failure.
set -uo pipefail

if [ $# -ne 3 ]; then
  echo "usage: srtm_shards_test.sh TINSMITH HGT WORKDIR" >&2
  exit 2
fi
tinsmith="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
hgt="$(cd "$(dirname "$2")" && pwd)/$(basename "$2")"
here="$(cd "$(dirname "$0")" && pwd)"
mkdir -p "$3"
work="$(cd "$3" && pwd)"
cd "$work" || exit 2
source "$here/local_cluster.sh"
budget=420
source "$here/test_steps.sh"

tolerance=10
shard_zoom=2
subtrees=$((4 ** shard_zoom))

# ---------------------------------------------------------------- the cluster
t0=$(date +%s.%N)
slurm_start "$work/cluster" || fatal "the local Slurm cluster did not start"
phase "cluster start" "$t0"
ok "one-node cluster up (node $slurm_node)"
find "$work" -mindepth 1 -maxdepth 1 ! -name cluster -exec rm -rf {} +

# ---------------------------------------------------------------- the data
[ -r "$hgt" ] || fatal "no SRTM tile at $hgt"
t0=$(date +%s.%N)
gdal_translate -q -of XYZ "$hgt" "$work/cells.xyz" || fatal "gdal_translate $hgt"
awk '{print $1, $2}' "$work/cells.xyz" | gdaltransform -s_srs EPSG:4326 -t_srs EPSG:32619 -output_xy \
  >"$work/xy.txt" || fatal "gdaltransform to EPSG:32619"
paste -d' ' "$work/xy.txt" <(awk '{print $3}' "$work/cells.xyz") | awk '$3 !~ /nan/ && $3 > -1000' \
  >"$work/srtm.xyz"
rm -f "$work/cells.xyz" "$work/xy.txt"
"$tinsmith" tin --points "$work/srtm.xyz" --crs EPSG:32619 --trim-hull 300 -o "$work/srtm.tin" -q \
  >"$work/tin.log" 2>&1 || { show "$work/tin.log"; fatal "tinsmith tin"; }
phase "SRTM TIN" "$t0"
vertices=$("$tinsmith" info "$work/srtm.tin" --json | python3 -c 'import json, sys; print(json.load(sys.stdin)["vertices"])')
expect "the SRTM TIN holds over a million vertices ($vertices)" test "${vertices:-0}" -gt 1000000

t0=$(date +%s.%N)
"$tinsmith" tile "$work/srtm.tin" -o "$work/one.3dtiles" --tolerance "$tolerance" --json \
  >"$work/one.json" 2>"$work/one.err" || { show "$work/one.err"; fatal "tinsmith tile (the single run)"; }
phase "single run ($(nproc) threads)" "$t0"
zooms=$(json "$work/one.json" 'len(d["zooms"])')
expect "the single run's pyramid goes below the shard zoom ($zooms zooms)" test "${zooms:-0}" -gt $((shard_zoom + 1))
# The failing task: the first zoom-2 subtree in the pyramid (task y·4 + x + 1).
victim=""
for k in $(seq 1 "$subtrees"); do
  key="tiles/$shard_zoom/$(((k - 1) % 4))/$(((k - 1) / 4)).glb"
  if [ -n "$(sqlite3 "$work/one.3dtiles" "select 1 from media where key = '$key'")" ]; then
    victim=$k
    break
  fi
done
[ -n "$victim" ] || fatal "no zoom-$shard_zoom tile in one.3dtiles"

# ---------------------------------------------------------------- 1. a failed shard
run="$work/run"
slurm_run() {
  "$tinsmith" slurm "$work/srtm.tin" -o "$work/merged.3dtiles" --shard-zoom "$shard_zoom" --workdir "$run" \
    --tolerance "$tolerance" --threads 1 --submit --json "$@" >"$run.out" 2>"$run.err"
}
t0=$(date +%s.%N)
slurm_run --sbatch-args=--hold || { show "$run.out" "$run.err"; fatal "tinsmith slurm --submit --hold"; }
phase "plan (tinsmith slurm)" "$t0"
submission "$run.out"
expect "17 tasks: the top and the $subtrees subtrees ($tasks)" test "$tasks" = "$(seq -s ' ' 0 "$subtrees")"
t0=$(date +%s.%N)
fail_one_shard "$run" "$array" "$merge" "$victim" 300
phase "17 shards on the cluster (release → merge cancelled)" "$t0"
expect_failed_shard "$run" "$array" "$merge" "$victim" "$work/merged.3dtiles"
kept=$(find "$run/shards" -maxdepth 1 -name '*.3dtiles' -type f | wc -l)
expect "the $subtrees other shards left their stores ($kept)" test "$kept" -eq "$subtrees"

# ---------------------------------------------------------------- 2. the retry
rm -rf "${run:?}/shards/$victim.3dtiles"
t0=$(date +%s.%N)
slurm_run --resume || { show "$run.out" "$run.err"; fatal "tinsmith slurm --resume --submit"; }
submission "$run.out"
expect "--resume resubmitted task $victim alone (tasks: $tasks)" test "$tasks" = "$victim"
merge_state=$(slurm_wait_job "$merge" "$(left 120)")
array_state=$(slurm_wait_job "$array" "$(left 30)")
phase "retry of task $victim and merge" "$t0"
expect "task $victim COMPLETED on its retry ($array_state)" test "$array_state" = COMPLETED
if ! expect "merge job $merge COMPLETED ($merge_state)" test "$merge_state" = COMPLETED; then
  show "$run/logs/merge.log" "$run.err"
fi
if [ -e "$work/merged.3dtiles" ]; then
  expect "merged store: the same bytes under every key as the single run" same_keys "$work/one.3dtiles" "$work/merged.3dtiles"
  expect "merged store: the same file, byte for byte, as the single run" cmp -s "$work/one.3dtiles" "$work/merged.3dtiles"
else
  bad "no merged store at $work/merged.3dtiles"
fi
# The merge's log ends with what each shard cost (tinsmith tile's "process:"
# line in each shard's log), measured here on the cluster.
costs=$(sed -n '/^the shards, from the last run in each log:/,$p' "$run/logs/merge.log")
listed=$(grep -c '^  shard [0-9]*: CPU ' <<<"$costs")
top_mb=$(awk '$2 == "0:" && $3 == "CPU" { print $8 }' <<<"$costs")
subtree_mb=$(awk '$1 == "shard" && $2 != "0:" && $3 == "CPU" && $8 + 0 > m { m = $8 + 0 } END { print m + 0 }' <<<"$costs")
one_mb=$(json "$work/one.json" 'round(d["peakMemoryBytes"] / 1e6)')
expect "the merge's log tells what each of the 17 shards cost ($listed; peak memory: top $top_mb MB, largest subtree $subtree_mb MB, single run $one_mb MB)" \
  test "$listed" -eq 17
expect "the largest subtree shard took at most a quarter of the single run's memory" \
  test "$((4 * ${subtree_mb:-0}))" -le "${one_mb:-0}" -a "${subtree_mb:-0}" -gt 0
# Each subtree shard reads its part of the .tin through the block index and
# says how much ("read the part of … : … X of Y MB").
parts=$(for t in $(seq 1 "$subtrees"); do grep -h '^read the part of' "$run/logs/shard-$t.log"; done)
read_most=$(awk '{ f = $(NF - 3) / $(NF - 1); if (f > m) m = f } END { printf "%.2f", m }' <<<"$parts")
expect "every subtree shard read at most a third of the .tin ($(wc -l <<<"$parts") reads, the most $read_most of it)" \
  awk -v m="$read_most" -v n="$(wc -l <<<"$parts")" 'BEGIN { exit !(n >= '"$subtrees"' && m > 0 && m <= 0.34) }'
missing_logs=""
for t in $(seq 0 "$subtrees"); do [ -s "$run/logs/shard-$t.log" ] || missing_logs+=" $t"; done
expect "a log per task and one for the merge${missing_logs:+ (missing:$missing_logs)}" \
  test -z "$missing_logs" -a -s "$run/logs/merge.log"
expect "task $victim's log holds its failure and its retry" \
  test "$(grep -c '^tinsmith shard' "$run/logs/shard-$victim.log")" -eq 2
exit 0
