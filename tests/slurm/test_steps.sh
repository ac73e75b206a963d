# The checks and Slurm look-ups the tests in tests/slurm share. Sourced, not
# run, after local_cluster.sh, by a script that sets `budget` (seconds for
# the whole test, cluster included) first:
#
#   source "$here/local_cluster.sh"; budget=300; source "$here/test_steps.sh"
#
# It starts the clock, counts checks (ok/bad/expect), and on exit stops the
# cluster, prints the time each phase took and `N passed, M failed`, and
# exits 1 on any failure.

started=$(date +%s.%N)
passed=0
failed=0
timings=()

seconds_since() { awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }
ok() { passed=$((passed + 1)); echo "ok    $*"; }
bad() { failed=$((failed + 1)); echo "FAIL  $*"; }
# expect WHAT COMMAND...: one check
expect() {
  local what="$1"
  shift
  if "$@"; then ok "$what"; else bad "$what"; fi
}
# show FILE...: the end of files, indented, for a failure's reader
show() {
  local f
  for f in "$@"; do
    echo "      --- $f"
    if [ -e "$f" ]; then tail -n 15 "$f" | sed 's/^/      /'; else echo "      (missing)"; fi
  done
}
# left SECONDS: SECONDS, or what is left of the budget if less
left() {
  local rest
  rest=$(awk -v a="$started" -v b="$(date +%s.%N)" -v n="$budget" 'BEGIN { printf "%d", n - (b - a) }')
  [ "$rest" -gt 5 ] || rest=5
  [ "$rest" -lt "$1" ] && echo "$rest" || echo "$1"
}
# phase NAME T0: records how long the phase took
phase() { timings+=("$1 $(seconds_since "$2") s"); }

finish() {
  local rc=$?
  trap - EXIT
  local t0
  t0=$(date +%s.%N)
  slurm_stop
  phase "cluster stop" "$t0"
  [ "$rc" -eq 0 ] || [ "$failed" -gt 0 ] || bad "the test stopped early (exit $rc)"
  echo "timings: ${timings[*]/%/;} total $(seconds_since "$started") s"
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ]
  exit $?
}
trap finish EXIT
trap 'exit 143' TERM INT
# fatal WHAT: a failure the rest cannot go on from
fatal() { bad "$*"; exit 1; }

# json FILE EXPRESSION: a value from a JSON file, as a Python expression on d
json() { python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); v = eval(sys.argv[2]); print(" ".join(map(str, v)) if isinstance(v, list) else v)' "$1" "$2"; }

# same_keys A B: the two stores hold the same keys with the same bytes
# (the media table of a .3dtiles archive, dumped by sqlite3 and compared)
same_keys() {
  sqlite3 "$1" "select key, hex(content) from media order by key" >"$1.dump" || return 1
  sqlite3 "$2" "select key, hex(content) from media order by key" >"$2.dump" || return 1
  cmp -s "$1.dump" "$2.dump" && return 0
  echo "      keys only in one of them:"
  comm -3 <(cut -d'|' -f1 "$1.dump") <(cut -d'|' -f1 "$2.dump") | head -n 10 | sed 's/^/        /'
  echo "      keys whose bytes differ:"
  comm -12 <(cut -d'|' -f1 "$1.dump") <(cut -d'|' -f1 "$2.dump") | while IFS= read -r key; do
    [ "$(grep -m1 -F "$key|" "$1.dump")" = "$(grep -m1 -F "$key|" "$2.dump")" ] || echo "        $key"
  done | head -n 10
  return 1
}

# submission FILE: the jobs of a `tinsmith slurm --submit --json` (its stdout
# in FILE): sets top (task 0 alone, which plans: empty when not submitted),
# array (the other tasks: empty when none was submitted), merge and tasks
# (every task id submitted, space-separated).
submission() {
  top=$(json "$1" 'd.get("top") or ""')
  array=$(json "$1" 'd.get("array") or ""')
  merge=$(json "$1" 'd["merge"]')
  tasks=$(json "$1" 'd["tasks"]')
}

# task_field JOB TASK FIELD: a field of one array task in scontrol's view
task_field() {
  scontrol -o show job "$1" 2>/dev/null | awk -v t="ArrayTaskId=$2" -v f="$3=" '
    { hit = 0; for (i = 1; i <= NF; i++) if ($i == t) hit = 1 }
    hit { for (i = 1; i <= NF; i++) if (index($i, f) == 1) print substr($i, length(f) + 1) }'
}
# job_field JOB FIELD: a field of a (non-array) job
job_field() { scontrol -o show job "$1" 2>/dev/null | grep -o "\b$2=[^ ]*" | head -n 1 | cut -d= -f2-; }
# failed_tasks JOB: the array tasks that ended FAILED, comma-separated
failed_tasks() {
  scontrol -o show job "$1" 2>/dev/null | grep 'JobState=FAILED' | grep -o 'ArrayTaskId=[0-9]*' | cut -d= -f2 | sort -n | paste -sd, -
}


# fail_one_shard WORKDIR ARRAY MERGE TASK SECONDS: the held jobs of a
# `tinsmith slurm --sbatch-args=--hold` (and the top job $top, when set)
# released after TASK's store path is taken by a folder holding a foreign
# file (tinsmith tile will not replace it), then waited for: the merge at
# most SECONDS, the array 30 s more (or what is left of the budget). Sets
# merge_state and array_state.
fail_one_shard() {
  local dir="$1" array="$2" merge="$3" task="$4" job
  mkdir -p "$dir/shards/$task.3dtiles"
  echo "not a tile store" >"$dir/shards/$task.3dtiles/notes.txt"
  for job in ${top:-} "$array" "$merge"; do
    scontrol release "$job" || fatal "scontrol release $job"
  done
  merge_state=$(slurm_wait_job "$merge" "$(left "$5")")
  array_state=$(slurm_wait_job "$array" "$(left 30)")
}

# expect_failed_shard WORKDIR ARRAY MERGE TASK OUTPUT: after fail_one_shard,
# TASK alone FAILED, the merge was CANCELLED by its dependency and wrote no
# store at OUTPUT, and the foreign file is untouched.
expect_failed_shard() {
  local dir="$1" array="$2" merge="$3" task="$4" output="$5" failed_list reason
  failed_list=$(failed_tasks "$array")
  expect "task $task FAILED and no other ($failed_list; array: $array_state)" test "$failed_list" = "$task"
  reason=$(job_field "$merge" Reason)
  expect "merge job $merge CANCELLED, DependencyNeverSatisfied ($merge_state, $reason)" \
    test "$merge_state" = CANCELLED -a "$reason" = DependencyNeverSatisfied
  expect "the cancelled merge wrote no store" test ! -e "$output"
  expect "the foreign file is untouched" test -f "$dir/shards/$task.3dtiles/notes.txt"
}
