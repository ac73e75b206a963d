#!/usr/bin/env bash
# ctest Slurm.ShardedTilingMatchesOneRun (issue 24): `tinsmith slurm` on a
# real one-node Slurm cluster (local_cluster.sh) gives the same store as one
# `tinsmith tile` run, and a failed shard is recovered with --resume.
#
#   bash tests/slurm/sharded_tiles_test.sh TINSMITH WORKDIR      (as root)
#
# The cluster first (WORKDIR/cluster), then a small TIN, a 1200 m × 600 m
# hill, so that half of the 16 subtrees at zoom 2 hold no terrain, tiled
# once with `tinsmith tile` (one.3dtiles). Then:
# - without --submit the command prints three sbatch commands that work as
#   printed (run by bash with a stand-in sbatch) and submits nothing;
# - `--shard-zoom 2 --submit --json`: task 0 (the plan and the top), then an
#   array of the 16 subtrees after it (a store each, built without their
#   ancestors, with task 0's plan) and a merge after them all, which leaves
#   out the subtrees not in the pyramid; the merged store holds the same
#   bytes under every key as one.3dtiles;
# - into a fresh workdir (its name with a space and a quote), the jobs
#   submitted on hold, and --resume refused while they wait; one shard's store path
#   then taken by a folder holding a foreign file (tinsmith will not replace
#   it) and the jobs released: that task fails, the merge is CANCELLED
#   (DependencyNeverSatisfied) and writes nothing;
# - the folder gone, `--resume --submit` resubmits that task alone and a new
#   merge, whose store again matches one.3dtiles; once more, with nothing
#   missing and task 0's tiler.plan removed (only the subtrees read it): a
#   merge alone, with no dependency.
# Everything stays in WORKDIR (the daemons' logs in WORKDIR/cluster/log);
# the waits are bounded by 300 s in all. Ends with `N passed, M failed`;
# exits 1 on any failure. tests/slurm/README.md says more.
set -uo pipefail

if [ $# -ne 2 ]; then
  echo "usage: sharded_tiles_test.sh TINSMITH WORKDIR" >&2
  exit 2
fi
tinsmith="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
here="$(cd "$(dirname "$0")" && pwd)"
mkdir -p "$2"
work="$(cd "$2" && pwd)"
cd "$work" || exit 2
source "$here/local_cluster.sh"

budget=300   # seconds for the whole test, cluster included
tile_opts=(--tolerance 0.2 --max-triangles 512)
shard_zoom=2
source "$here/test_steps.sh"

# ---------------------------------------------------------------- the cluster
# First, so that its first scheduling pass (about 3 s after slurmctld
# starts) comes while the single run tiles; and before WORKDIR is emptied,
# so that jobs a killed run left are stopped first (slurm_start finds them
# by the pid files in WORKDIR/cluster).
t0=$(date +%s.%N)
slurm_start "$work/cluster" || fatal "the local Slurm cluster did not start"
phase "cluster start" "$t0"
ok "one-node cluster up (node $slurm_node, $(grep -o 'SlurmctldPort=[0-9]*' "$SLURM_CONF"))"
find "$work" -mindepth 1 -maxdepth 1 ! -name cluster -exec rm -rf {} +

# ---------------------------------------------------------------- the data
t0=$(date +%s.%N)
"$tinsmith" tin --points 'synthetic:grid?nx=121&ny=61&spacing=10&x0=430000&y0=4515000&surface=hill&z0=1600&scale=80&noise=0.5' \
  --crs EPSG:26912 -o "$work/site.tin" -q >"$work/tin.log" 2>&1 || { show "$work/tin.log"; fatal "tinsmith tin"; }
"$tinsmith" tile "$work/site.tin" -o "$work/one.3dtiles" "${tile_opts[@]}" --json >"$work/one.json" 2>"$work/one.err" \
  || { show "$work/one.err"; fatal "tinsmith tile (the single run)"; }
phase "tin + single tile run" "$t0"
zooms=$(json "$work/one.json" 'len(d["zooms"])')
expect "the single run's pyramid has at least 3 zooms ($zooms)" test "${zooms:-0}" -ge 3
in_pyramid=$(json "$work/one.json" "[z['tiles'] for z in d['zooms'] if z['zoom'] == $shard_zoom][0]")
subtrees=$((4 ** shard_zoom))
expect "some zoom-$shard_zoom subtrees hold terrain and some do not ($in_pyramid of $subtrees)" \
  test "${in_pyramid:-0}" -gt 0 -a "${in_pyramid:-0}" -lt "$subtrees"

"$tinsmith" slurm --help >/dev/null 2>&1 || fatal "tinsmith has no slurm command ($tinsmith slurm --help fails)"

# run_slurm WORKDIR OUTPUT ARGS...: tinsmith slurm on site.tin, stdout in
# WORKDIR.out, stderr in WORKDIR.err
run_slurm() {
  local dir="$1" out="$2"
  shift 2
  "$tinsmith" slurm "$work/site.tin" -o "$out" --shard-zoom "$shard_zoom" --workdir "$dir" \
    "${tile_opts[@]}" --threads 1 "$@" >"$dir.out" 2>"$dir.err"
}

# ---------------------------------------------------------------- without --submit
rc=0
run_slurm "$work/plan" "$work/plan.3dtiles" || rc=$?
if [ "$rc" -eq 0 ]; then
  printed=$(cat "$work/plan.out" "$work/plan.err" | grep 'sbatch ')
  expect "without --submit: three sbatch commands printed" test "$(grep -c 'sbatch ' <<<"$printed")" -eq 3
  # Run as printed, with a stand-in sbatch that answers 4241 for task 0's
  # array and 4242 for the subtrees': they must wait for task 0, and the
  # merge for every task.
  wanted="--dependency=afterok:4241_0:$(seq -s: 1 "$subtrees" | sed 's/[0-9][0-9]*/4242_&/g') "
  stand_in=$(bash -c 'sbatch() { case " $* " in *" --array=0 "*) echo 4241 ;;
    *" --array="*" --dependency=afterok:4241_0 "*) echo 4242 ;; *) echo "sbatch $*" ;; esac; }
'"$printed" 2>&1)
  if ! expect "without --submit: the printed commands, run as printed, make the subtrees wait for task 0 and the merge for the $((subtrees + 1)) tasks" \
    grep -qF -- "$wanted" <<<"$stand_in"; then
    echo "      printed:"
    sed 's/^/        /' <<<"$printed"
    echo "      run with a stand-in sbatch (task 0's id 4241, the subtrees' 4242):"
    sed 's/^/        /' <<<"$stand_in"
  fi
  expect "without --submit: plan.json, shard.sh and merge.sh written, and no tiler.plan (task 0 plans)" \
    test -s "$work/plan/plan.json" -a -s "$work/plan/shard.sh" -a -s "$work/plan/merge.sh" \
    -a ! -e "$work/plan/tiler.plan"
  expect "without --submit: nothing submitted" test -z "$(squeue -h -o %i)"
else
  bad "tinsmith slurm without --submit (exit $rc)"
  show "$work/plan.out" "$work/plan.err"
fi

# ---------------------------------------------------------------- 1. the sharded run
run="$work/run"
t0=$(date +%s.%N)
rc=0
run_slurm "$run" "$work/merged.3dtiles" --submit --json || rc=$?
if [ "$rc" -ne 0 ]; then
  show "$run.out" "$run.err"
  fatal "tinsmith slurm --submit (exit $rc)"
fi
submission "$run.out"
expect "--submit --json: the top and the $subtrees subtrees (tasks: $tasks), the top a job of its own ($top)" \
  test "$tasks" = "$(seq -s ' ' 0 "$subtrees")" -a -n "$top"
merge_state=$(slurm_wait_job "$merge" "$(left 240)")
phase "sharded run (submit → merge done)" "$t0"
top_state=$(slurm_wait_job "$top" "$(left 30)")
array_state=$(slurm_wait_job "$array" "$(left 30)")
expect "the top job $top COMPLETED ($top_state), and tiler.plan is there" test "$top_state" = COMPLETED -a -s "$run/tiler.plan"
expect "array job $array: every task COMPLETED ($array_state)" test "$array_state" = COMPLETED
if ! expect "merge job $merge COMPLETED ($merge_state)" test "$merge_state" = COMPLETED; then
  show "$run/logs/merge.log" "$run.err"
fi
stores=$(find "$run/shards" -maxdepth 1 -name '*.3dtiles' | wc -l)
expect "shards: the top and $subtrees subtree stores, $in_pyramid of them in the pyramid ($stores stores)" \
  test "$stores" -eq $((subtrees + 1)) -a -e "$run/shards/0.3dtiles"
missing_logs=""
for t in $(seq 0 "$subtrees"); do [ -e "$run/logs/shard-$t.log" ] || missing_logs+=" $t"; done
expect "a log per task and one for the merge${missing_logs:+ (missing:$missing_logs)}" \
  test -z "$missing_logs" -a -s "$run/logs/merge.log"
if [ -e "$work/merged.3dtiles" ]; then
  expect "merged store: the same bytes under every key as the single run" same_keys "$work/one.3dtiles" "$work/merged.3dtiles"
  expect "merged store: the same file, byte for byte, as the single run" cmp -s "$work/one.3dtiles" "$work/merged.3dtiles"
else
  bad "no merged store at $work/merged.3dtiles"
fi

# the task whose store the second run finds taken: the first subtree in the pyramid
victim=""
for t in $(seq 1 "$subtrees"); do
  [ -e "$run/shards/$t.3dtiles" ] && { victim=$t; break; }
done
[ -n "$victim" ] || fatal "no subtree store in $run/shards to take the place of"

# ---------------------------------------------------------------- 2. a failed shard
# A fresh workdir (tinsmith slurm takes no other without --resume), the jobs
# submitted on hold (--sbatch-args, passed to both), then one subtree's
# store path taken by a folder holding a foreign file, then the jobs
# released: tinsmith tile will not replace that folder.
# A space and a quote in the folder's name: the scripts, the logs' paths
# (sbatch --output) and the merge take any path.
again="$work/again it's"
t0=$(date +%s.%N)
rc=0
run_slurm "$again" "$work/merged-again.3dtiles" --submit --json --sbatch-args=--hold || rc=$?
if [ "$rc" -ne 0 ]; then
  show "$again.out" "$again.err"
  fatal "tinsmith slurm --submit --sbatch-args=--hold (exit $rc)"
fi
submission "$again.out"
held=$(scontrol -o show job "$array" 2>/dev/null | grep -o 'Reason=[A-Za-z]*' | sort -u | paste -sd, -)
expect "--sbatch-args=--hold reaches the top job $top ($(job_field "$top" Reason)), the array job $array ($held) and the merge job $merge ($(job_field "$merge" Reason))" \
  test "$held" = Reason=JobHeldUser -a "$(job_field "$merge" Reason)" = JobHeldUser \
  -a "$(job_field "$top" Reason)" = JobHeldUser
# While they wait, --resume refuses to submit them again.
held_top=$top held_array=$array held_merge=$merge
rc=0
run_slurm "$again" "$work/merged-again.3dtiles" --resume --submit --json || rc=$?
expect "--resume while the jobs are queued: refused (exit $rc), naming them, and nothing more queued" \
  test "$rc" -eq 2 -a "$(squeue -h -o %i | cut -d_ -f1 | sort -u | wc -l)" -eq 3
grep -q "still queued or running" "$again.err" || show "$again.err"
top=$held_top array=$held_array merge=$held_merge
fail_one_shard "$again" "$array" "$merge" "$victim" 240
phase "failing run (release → merge cancelled)" "$t0"
expect_failed_shard "$again" "$array" "$merge" "$victim" "$work/merged-again.3dtiles"
code=$(task_field "$array" "$victim" ExitCode)
if ! expect "task $victim exited with 5, i/o ($code)" test "$code" = 5:0; then
  show "$again/logs/shard-$victim.log"
fi
refusal=$(grep -m1 'ERROR' "$again/logs/shard-$victim.log" 2>/dev/null | cut -c1-160)
expect "task $victim's log says why (${refusal:-no ERROR line})" test -n "$refusal"

# ---------------------------------------------------------------- 3. resume
rm -rf "${again:?}/shards/$victim.3dtiles"
t0=$(date +%s.%N)
rc=0
run_slurm "$again" "$work/merged-again.3dtiles" --resume --submit --json || rc=$?
if [ "$rc" -ne 0 ]; then
  show "$again.out" "$again.err"
  fatal "tinsmith slurm --resume --submit (exit $rc)"
fi
submission "$again.out"
expect "--resume resubmitted task $victim alone (tasks: $tasks; top: '$top')" test "$tasks" = "$victim" -a -z "$top"
merge_state=$(slurm_wait_job "$merge" "$(left 120)")
array_state=$(slurm_wait_job "$array" "$(left 30)")
phase "resume (submit → merge done)" "$t0"
ran=$(scontrol -o show job "$array" 2>/dev/null | grep -o 'ArrayTaskId=[0-9,-]*' | cut -d= -f2 | paste -sd, -)
expect "the resubmitted array job $array ran task $victim only (${ran:-not an array}: $array_state)" \
  test "$ran" = "$victim" -a "$array_state" = COMPLETED
if ! expect "new merge job $merge COMPLETED ($merge_state)" test "$merge_state" = COMPLETED; then
  show "$again/logs/merge.log" "$again.err"
fi
if [ -e "$work/merged-again.3dtiles" ]; then
  expect "resumed store: the same bytes under every key as the single run" same_keys "$work/one.3dtiles" "$work/merged-again.3dtiles"
else
  bad "no store at $work/merged-again.3dtiles after the resume"
fi

# ---------------------------------------------------------------- 4. nothing to resume
# The plan gone too: no subtree is left to read it, so the top is not rerun.
t0=$(date +%s.%N)
rm -f "$again/tiler.plan"
rc=0
run_slurm "$again" "$work/merged-again.3dtiles" --resume --submit --json || rc=$?
if [ "$rc" -ne 0 ]; then
  show "$again.out" "$again.err"
  fatal "tinsmith slurm --resume --submit with every shard done (exit $rc)"
fi
submission "$again.out"
dependency=$(job_field "$merge" Dependency)
expect "--resume with every shard done: no tasks, no top, no array, a merge with no dependency (tasks: '$tasks', top: '$top', array: '$array', $dependency)" \
  test -z "$tasks" -a -z "$top" -a -z "$array" -a "$dependency" = "(null)"
merge_state=$(slurm_wait_job "$merge" "$(left 60)")
phase "resume with nothing missing" "$t0"
expect "that merge job $merge COMPLETED ($merge_state)" test "$merge_state" = COMPLETED
expect "and its store holds the same bytes under every key as the single run" \
  same_keys "$work/one.3dtiles" "$work/merged-again.3dtiles"
exit 0
