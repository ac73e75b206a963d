#!/usr/bin/env bash
# ctest Slurm.SrtmSixteenShards (issue 24): a real DEM, SRTM N44W072 (the
# 3″ tile of ../shared/data/srtm, 1.44 M cells projected to UTM 19N), tiled
# at 10 m as 16 shards on a real one-node Slurm cluster (local_cluster.sh):
# the merged store holds the bytes of one `tinsmith tile` run, and a shard
# that fails is retried with --resume, after which the merge runs.
#
#   bash tests/slurm/srtm_shards_test.sh TINSMITH HGT WORKDIR      (as root)
#
# The cluster first (WORKDIR/cluster), then the points (every cell a point,
# projected by gdaltransform) and their TIN built on the cluster by `tinsmith
# slurm-tin` in blocks of 100 000 points, one block task failing and retried
# with --resume: the same bytes as `tinsmith tin --block-points` on one
# machine, each task in at most a third of the memory of the TIN at once.
# Then the single tiling run (one.3dtiles, every core). Then `tinsmith slurm --shard-zoom 2 --submit
# --json --sbatch-args=--hold`: the top (task 0, which plans the pyramid
# once), the 16 subtrees as an array after it and the merge after them all,
# every job on hold; one subtree's store path is taken by a
# folder holding a foreign file (tinsmith will not replace it) and the jobs
# released. That task alone FAILS, the merge is CANCELLED and writes
# nothing, the 16 other shards are kept. The folder removed, `--resume
# --submit` runs that task again and a new merge, whose store is the single
# run's, byte for byte. The waits are bounded by 480 s in all; everything
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
budget=480
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
phase "SRTM points" "$t0"

# ---------------------------------------------------------------- 0. the TIN by blocks
# One machine first: the TIN at once (for its memory) and by blocks (for its bytes).
t0=$(date +%s.%N)
tin_options=(--points "$work/srtm.xyz" --crs EPSG:32619 --block-points 100000 --max-circumradius 150)
peak_kb() { python3 -c 'import resource, subprocess, sys
r = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss if r.returncode == 0 else -1)' "$@"; }
whole_kb=$(peak_kb "$tinsmith" tin --points "$work/srtm.xyz" --crs EPSG:32619 -o "$work/whole.tin" -q)
expect "tinsmith tin of every point at once ($whole_kb KB at peak)" test "$whole_kb" -gt 0
"$tinsmith" tin "${tin_options[@]}" -o "$work/local.tin" -q >"$work/local.log" 2>&1 ||
  { show "$work/local.log"; fatal "tinsmith tin --block-points"; }
rm -f "$work/whole.tin"
phase "SRTM TIN on one machine, at once and by blocks" "$t0"
# Then on the cluster, one block task failing (its triangles' path taken by
# a folder holding a foreign file) and retried.
tin_run="$work/run-tin"
slurm_tin() {
  "$tinsmith" slurm-tin "${tin_options[@]}" -o "$work/srtm.tin" --workdir "$tin_run" --submit --json \
    "$@" >"$tin_run.out" 2>"$tin_run.err"
}
t0=$(date +%s.%N)
slurm_tin --sbatch-args=--hold || { show "$tin_run.out" "$tin_run.err"; fatal "tinsmith slurm-tin --submit --hold"; }
block_tasks=$(json "$tin_run.out" 'd["blockTasks"]')
array=$(json "$tin_run.out" 'd["array"]')
assemble=$(json "$tin_run.out" 'd["assemble"]')
expect "slurm-tin prepared the points in blocks ($block_tasks tasks)" test "${block_tasks:-0}" -ge 9
tin_victim=3
mkdir -p "$tin_run/triangles/$tin_victim.tri"
echo "not triangles" >"$tin_run/triangles/$tin_victim.tri/notes.txt"
scontrol release "$array" && scontrol release "$assemble" || fatal "scontrol release $array $assemble"
assemble_state=$(slurm_wait_job "$assemble" "$(left 120)")
array_state=$(slurm_wait_job "$array" "$(left 30)")
expect "block task $tin_victim FAILED and no other ($(failed_tasks "$array"); array: $array_state)" \
  test "$(failed_tasks "$array")" = "$tin_victim"
expect "the assembly $assemble CANCELLED ($assemble_state) and wrote no TIN" \
  test "$assemble_state" = CANCELLED -a ! -e "$work/srtm.tin"
rm -rf "${tin_run:?}/triangles/$tin_victim.tri"
slurm_tin --resume || { show "$tin_run.out" "$tin_run.err"; fatal "tinsmith slurm-tin --resume --submit"; }
expect "--resume resubmitted block task $tin_victim alone ($(json "$tin_run.out" 'd["tasks"]'))" \
  test "$(json "$tin_run.out" 'd["tasks"]')" = "$tin_victim"
assemble=$(json "$tin_run.out" 'd["assemble"]')
assemble_state=$(slurm_wait_job "$assemble" "$(left 120)")
phase "SRTM TIN by blocks on the cluster (a failed task, its retry, the assembly)" "$t0"
if ! expect "the assembly $assemble COMPLETED ($assemble_state)" test "$assemble_state" = COMPLETED; then
  show "$tin_run/logs/assemble.log" "$tin_run.err"
fi
expect "the cluster's TIN has the bytes of the one machine's by blocks" cmp -s "$work/srtm.tin" "$work/local.tin"
block_kb=$(awk '/^  task [0-9]*: CPU / && $8 + 0 > m { m = $8 + 0 } END { printf "%d", m * 1000000 / 1024 }' \
  "$tin_run/logs/assemble.log")
expect "each block task took at most a third of the memory of the TIN at once (at most $block_kb KB, at once $whole_kb KB)" \
  test "${block_kb:-0}" -gt 0 -a "$((3 * ${block_kb:-0}))" -le "$whole_kb"
[ -e "$work/srtm.tin" ] || fatal "no TIN to tile"
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

# A shard zoom above the mosaic zoom (2 for 1.44 M vertices: the top is
# fitted to zoom 2's tiles) is refused on the login node, nothing written.
"$tinsmith" slurm "$work/srtm.tin" -o "$work/above.3dtiles" --shard-zoom 1 --workdir "$work/above" \
  --tolerance "$tolerance" >"$work/above.out" 2>"$work/above.err" && above_rc=0 || above_rc=$?
expect "--shard-zoom 1 is refused (exit $above_rc) before a file is written, naming --shard-zoom 2" \
  test "$above_rc" = 2 -a ! -e "$work/above" -a ! -e "$work/above.3dtiles" \
  -a -n "$(grep -- '--shard-zoom 2 or more' "$work/above.err")"

# ---------------------------------------------------------------- 1. a failed shard
run="$work/run"
slurm_run() {
  "$tinsmith" slurm "$work/srtm.tin" -o "$work/merged.3dtiles" --shard-zoom "$shard_zoom" --workdir "$run" \
    --tolerance "$tolerance" --threads 1 --submit --json "$@" >"$run.out" 2>"$run.err"
}
t0=$(date +%s.%N)
slurm_run --sbatch-args=--hold || { show "$run.out" "$run.err"; fatal "tinsmith slurm --submit --hold"; }
phase "tinsmith slurm (the scripts, submitted)" "$t0"
submission "$run.out"
expect "17 tasks: the top (which plans, job $top) and the $subtrees subtrees after it ($tasks)" \
  test "$tasks" = "$(seq -s ' ' 0 "$subtrees")" -a -n "$top"
t0=$(date +%s.%N)
fail_one_shard "$run" "$array" "$merge" "$victim" 300
phase "the plan and the top, then the 16 subtrees, on the cluster (release → merge cancelled)" "$t0"
expect_failed_shard "$run" "$array" "$merge" "$victim" "$work/merged.3dtiles"
kept=$(find "$run/shards" -maxdepth 1 -name '*.3dtiles' -type f | wc -l)
expect "the $subtrees other shards left their stores ($kept)" test "$kept" -eq "$subtrees"

# ---------------------------------------------------------------- 2. the retry
rm -rf "${run:?}/shards/$victim.3dtiles"
t0=$(date +%s.%N)
slurm_run --resume || { show "$run.out" "$run.err"; fatal "tinsmith slurm --resume --submit"; }
submission "$run.out"
expect "--resume resubmitted task $victim alone (tasks: $tasks; top: '$top')" test "$tasks" = "$victim" -a -z "$top"
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
# What a process holds before its part (the libraries, PROJ): a tile run of
# a TIN of eight triangles. A shard's own memory is its peak less that.
printf '%s\n' 300000 4900000 10 300100 4900000 11 300200 4900000 12 300000 4900100 13 \
  300100 4900100 15 300200 4900100 14 300000 4900200 12 300100 4900200 13 300200 4900200 11 |
  paste -d ' ' - - - >"$work/tiny.xyz"
"$tinsmith" tin --points "$work/tiny.xyz" --crs EPSG:32619 -o "$work/tiny.tin" -q ||
  fatal "tinsmith tin (a TIN of eight triangles)"
process_kb=$(peak_kb "$tinsmith" tile "$work/tiny.tin" --tolerance 1 -o "$work/tiny.3dtiles" -q)
process_mb=$(( process_kb * 1024 / 1000000 ))
expect "the largest subtree shard's own memory (its peak less the process's $process_mb MB) is at most a quarter of the single run's" \
  test "$((4 * (${subtree_mb:-0} - process_mb)))" -le "$(( ${one_mb:-0} - process_mb ))" -a "${subtree_mb:-0}" -gt 0 -a "$process_kb" -gt 0
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
# Over 2^18 vertices (K = 2, the shard zoom) the top builds no tile: every
# subtree hands its zoom-2 tile's surface over, and the merge builds the
# tiles above zoom 2 from them.
handed=$(for t in $(seq 1 "$subtrees"); do grep -h 'this shard hands over' "$run/logs/shard-$t.log" | tail -1; done |
  awk '{ n += $(NF - 2) } END { print n + 0 }')
zoom2=$(sqlite3 "$work/one.3dtiles" "select count(*) from media where key like 'tiles/2/%'")
expect "task 0 leaves the tiles above zoom 2 to the merge, handing over no surface; the subtrees hand over $handed surfaces, one for each of the one run's $zoom2 zoom-2 tiles" \
  test -n "$(grep 'the tiles above zoom 2 are the merge.s.*hands over 0 of them' "$run/logs/shard-0.log")" -a "$handed" -eq "${zoom2:-0}" -a "${zoom2:-0}" -gt 0
expect "task $victim's log holds its failure and its retry" \
  test "$(grep -c '^tinsmith shard' "$run/logs/shard-$victim.log")" -eq 2
exit 0
