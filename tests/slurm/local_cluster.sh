# A one-node Slurm cluster for the tests, from the Debian packages
# (slurmctld slurmd slurm-client munge, installed by tools/setup.sh): its own
# munge key, configuration, state, spool and logs under one folder, nothing
# written outside it, no systemd, no cgroups, no accounting daemon. Sourced,
# not run:
#
#   source tests/slurm/local_cluster.sh
#   slurm_start BASE || exit 1        # exports SLURM_CONF, sets slurm_node
#   trap slurm_stop EXIT
#   id=$(sbatch --parsable --wrap true)
#   state=$(slurm_wait_job "$id" 60)  # COMPLETED, FAILED, CANCELLED, ...
#   slurm_stop
#
# Needs root: the daemons run as root and so do the jobs. Every wait is
# bounded. BASE/log keeps the daemons' logs after slurm_stop; slurm_start
# wipes BASE's cluster folders first, stopping whatever an earlier run under
# the same BASE left behind (a killed test, say). Two clusters at once need
# two BASEs; each picks its own free ports. tests/slurm/README.md lists the
# traps of running Slurm in a container that this file steps around.

slurm_base=""
slurm_node=""

# _slurm_say MESSAGE: a line on stderr.
_slurm_say() { echo "local_cluster: $*" >&2; }

# _slurm_alive PID [NAME]: PID is a live process (a zombie is not; PID 1 of
# these containers reaps orphans late, and kill -0 succeeds on a zombie),
# named NAME when given. Reads /proc, so procps is not needed.
_slurm_alive() {
  local pid="$1" name="${2:-}" stat comm rest
  [[ "$pid" =~ ^[0-9]+$ ]] || return 1
  { read -r stat <"/proc/$pid/stat"; } 2>/dev/null || return 1
  [ -n "$stat" ] || return 1
  rest=${stat##*) }            # after the name: "S ppid pgrp ..."
  [ "${rest:0:1}" != Z ] || return 1
  [ -z "$name" ] && return 0
  comm=${stat#*(}
  comm=${comm%) *}
  [ "$comm" = "$name" ]
}

# _slurm_stop_pid PID NAME SECONDS: TERM, wait up to SECONDS, then KILL.
_slurm_stop_pid() {
  local pid="$1" name="$2" seconds="$3" i
  _slurm_alive "$pid" "$name" || return 0
  kill -TERM "$pid" 2>/dev/null
  for ((i = 0; i < seconds * 10; i++)); do
    _slurm_alive "$pid" || return 0
    sleep 0.1
  done
  _slurm_say "$name (pid $pid) still up ${seconds} s after TERM: KILL"
  kill -KILL "$pid" 2>/dev/null
  for ((i = 0; i < 20; i++)); do
    _slurm_alive "$pid" || return 0
    sleep 0.1
  done
}

# _slurm_reap_steps CONF: kills the slurmstepd processes of the cluster
# configured by CONF, and their jobs. They outlive slurmd and slurmctld and
# ignore TERM (so does an srun inside a job); they are ours when their
# environment, inherited from our slurmd, holds SLURM_CONF=CONF.
_slurm_reap_steps() {
  local conf="$1" f pid stat ppid rest steps=() groups=() g
  for f in /proc/[0-9]*/stat; do
    pid=${f#/proc/}
    pid=${pid%/stat}
    _slurm_alive "$pid" slurmstepd || continue
    tr '\0' '\n' <"/proc/$pid/environ" 2>/dev/null | grep -qxF "SLURM_CONF=$conf" || continue
    steps+=("$pid")
  done
  [ ${#steps[@]} -gt 0 ] || return 0
  # the job processes: children of a step, each leading its process group
  for f in /proc/[0-9]*/stat; do
    { read -r stat <"$f"; } 2>/dev/null || continue
    rest=${stat##*) }
    read -r _ ppid g _ <<<"$rest"
    for pid in "${steps[@]}"; do
      [ "$ppid" = "$pid" ] && [ "$g" != 0 ] && groups+=("$g")
    done
  done
  for g in "${groups[@]}"; do kill -TERM -- "-$g" 2>/dev/null; done
  [ ${#groups[@]} -eq 0 ] || sleep 0.5
  for g in "${groups[@]}"; do kill -KILL -- "-$g" 2>/dev/null; done
  for pid in "${steps[@]}"; do kill -KILL "$pid" 2>/dev/null; done
  _slurm_say "killed slurmstepd ${steps[*]} left behind, and their jobs"
}

# _slurm_shutdown BASE: stops the cluster under BASE, whoever started it:
# cancels every job and waits (up to 10 s) for the running ones to end, so
# that no step outlives the daemons; stops slurmd and slurmctld together,
# then munged (they need it to the end), each by the pid its pid file
# records and only when that process still has the daemon's name; kills any
# step left. Does nothing when nothing runs. Always returns 0.
_slurm_shutdown() {
  local base="$1" conf="$1/etc/slurm.conf" ctld="" pid name i stoppers=()
  [ -f "$conf" ] || return 0
  [ -s "$base/run/slurmctld.pid" ] && read -r ctld <"$base/run/slurmctld.pid"
  if _slurm_alive "$ctld" slurmctld; then
    SLURM_CONF="$conf" scancel --quiet --partition=tests 2>/dev/null
    for ((i = 0; i < 100; i++)); do
      [ -z "$(SLURM_CONF="$conf" squeue -h -t CF,R,CG -o %i 2>/dev/null)" ] && break
      sleep 0.1
    done
  fi
  for name in slurmd slurmctld; do
    pid=""
    [ -s "$base/run/$name.pid" ] && read -r pid <"$base/run/$name.pid"
    _slurm_stop_pid "$pid" "$name" 10 &
    stoppers+=($!)
  done
  wait "${stoppers[@]}"   # those two only, not the caller's own background jobs
  pid=""
  [ -s "$base/run/munged.pid" ] && read -r pid <"$base/run/munged.pid"
  _slurm_stop_pid "$pid" munged 10
  _slurm_reap_steps "$conf"
  return 0
}

# _slurm_sockets BASE: the folder of munged's socket and slurmd's spool
# (the steps' sockets): BASE/run, or when that path is too long for a Unix
# socket (108 bytes, and slurmd adds NODE_JOB.STEP) a short folder in /tmp
# named after BASE, the same on every call.
_slurm_sockets() {
  local base="$1" node
  node=$(hostname -s)
  if [ $(( ${#base} + ${#node} )) -le 60 ]; then
    echo "$base/run"
  else
    echo "/tmp/tinsmith-slurm-$(printf '%s' "$base" | cksum | cut -d' ' -f1)"
  fi
}

# _slurm_port_taken PORT: something holds the TCP port (IPv4 or IPv6, any
# state), from /proc/net/tcp*.
_slurm_port_taken() {
  local hex
  hex=$(printf '%04X' "$1")
  cat /proc/net/tcp /proc/net/tcp6 2>/dev/null | awk -v p=":$hex" 'substr($2, length($2) - 4) == p { found = 1 } END { exit !found }'
}

# _slurm_free_ports BASE: two free TCP ports, one after the other, for
# slurmctld and slurmd: from 16800 on (above Slurm's own 6817/6818), at a
# start that depends on BASE so that two clusters started at once are
# unlikely to race for the same pair.
_slurm_free_ports() {
  local start port i
  start=$(( 16800 + ($(printf '%s' "$1" | cksum | cut -d' ' -f1) % 100) * 2 ))
  for ((i = 0; i < 200; i++)); do
    port=$(( start + 2 * i ))
    _slurm_port_taken "$port" || _slurm_port_taken $(( port + 1 )) || { echo "$port $(( port + 1 ))"; return 0; }
  done
  return 1
}

# slurm_start BASE: starts munged, slurmctld and slurmd under BASE and waits
# (up to 30 s) for the node to be idle. Exports SLURM_CONF (every Slurm
# client needs it, sbatch in tinsmith too; jobs inherit it) and sets
# slurm_node. Returns 1 with the reason on stderr, having stopped whatever
# it started.
slurm_start() {
  local base ports ctld_port slurmd_port sockets cpus mem_mb real_mem state i tool
  [ $# -eq 1 ] || { _slurm_say "usage: slurm_start BASE"; return 2; }
  for tool in munged mungekey munge unmunge slurmctld slurmd sbatch scontrol sinfo squeue scancel hostname awk cksum; do
    command -v "$tool" >/dev/null 2>&1 || { _slurm_say "$tool is missing (bash tools/setup.sh installs slurmctld slurmd slurm-client munge)"; return 1; }
  done
  [ "$(id -u)" -eq 0 ] || { _slurm_say "the local cluster runs its daemons and jobs as root: run as root"; return 1; }
  mkdir -p "$1" || return 1
  base=$(cd "$1" && pwd)
  slurm_node=$(hostname -s)
  [ -n "$slurm_node" ] || { _slurm_say "hostname -s is empty"; return 1; }

  # Whatever an earlier run under this BASE left running goes first: its
  # controller would hold the ports and answer with the old key.
  _slurm_shutdown "$base"
  sockets=$(_slurm_sockets "$base")
  rm -rf "$base/etc" "$base/run" "$base/state" "$base/log" "$sockets"
  mkdir -p -m 0755 "$base/etc" "$base/run" "$base/state" "$base/log" "$sockets" || return 1
  chmod 0755 "$sockets"   # munged: the socket's folder must be a+x, not group/other writable
  slurm_base="$base"

  # munge, with a key of our own (not /etc/munge/munge.key)
  mungekey --create --keyfile="$base/etc/munge.key" >/dev/null 2>"$base/log/mungekey.err" \
    || { _slurm_say "mungekey failed: $(cat "$base/log/mungekey.err")"; return 1; }
  chmod 0400 "$base/etc/munge.key"
  munged --key-file="$base/etc/munge.key" --socket="$sockets/munge.socket" \
    --pid-file="$base/run/munged.pid" --log-file="$base/log/munged.log" \
    --seed-file="$base/state/munged.seed" </dev/null >/dev/null 2>"$base/log/munged.err" \
    || { _slurm_say "munged failed: $(tail -n 3 "$base/log/munged.err" "$base/log/munged.log" 2>/dev/null)"; slurm_stop; return 1; }
  munge -S "$sockets/munge.socket" -n 2>/dev/null | unmunge -S "$sockets/munge.socket" >/dev/null 2>&1 \
    || { _slurm_say "munge credentials do not round-trip (munged.log: $(tail -n 3 "$base/log/munged.log"))"; slurm_stop; return 1; }

  ports=$(_slurm_free_ports "$base") || { _slurm_say "no two free TCP ports from 16800 on"; slurm_stop; return 1; }
  read -r ctld_port slurmd_port <<<"$ports"
  cpus=$(nproc)
  # RealMemory above what slurmd measures makes the node INVALID (nothing
  # runs): 95 % of the total `free -m` shows. Without DefMemPerCPU each job
  # would ask for all of it and the jobs would run one at a time.
  mem_mb=$(awk '/^MemTotal:/ { print int($2 / 1024) }' /proc/meminfo)
  real_mem=$(( mem_mb * 95 / 100 ))
  export SLURM_CONF="$base/etc/slurm.conf"
  cat >"$SLURM_CONF" <<EOF
# tests/slurm/local_cluster.sh: one node, everything under $base
ClusterName=tinsmith
SlurmctldHost=${slurm_node}(127.0.0.1)
SlurmctldPort=${ctld_port}
SlurmdPort=${slurmd_port}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
# Slurm does not ask munged where its socket is
AuthInfo=socket=${sockets}/munge.socket
StateSaveLocation=${base}/state
SlurmdSpoolDir=${sockets}/spool
SlurmctldPidFile=${base}/run/slurmctld.pid
SlurmdPidFile=${base}/run/slurmd.pid
SlurmctldLogFile=${base}/log/slurmctld.log
SlurmdLogFile=${base}/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# no cgroups (so --mem is a reservation, not a limit), no accounting daemon;
# finished jobs are listed by sacct -c from this file
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=${base}/log/jobcomp.txt
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true
# cores and memory are what jobs take; a job with no --mem takes its CPU's share
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=$(( real_mem / cpus ))
# schedule as soon as a job is submitted or ends (the default waits 3 s)
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
# a job whose dependency failed is CANCELLED, not left pending for ever
DependencyParameters=kill_invalid_depend
# refuse at submit what the node can never run
EnforcePartLimits=ALL
ReturnToService=2
# scontrol show job knows finished jobs for 10 minutes
MinJobAge=600
NodeName=${slurm_node} NodeAddr=127.0.0.1 CPUs=${cpus} RealMemory=${real_mem} State=UNKNOWN
PartitionName=tests Nodes=${slurm_node} Default=YES MaxTime=INFINITE State=UP
EOF
  mkdir -p -m 0755 "$sockets/spool"

  # Both daemons fork into the background and write their pid files; their
  # stdout and stderr go to files, so that nothing they leave holds the
  # caller's pipes (ctest waits for those).
  slurmctld -f "$SLURM_CONF" </dev/null >/dev/null 2>"$base/log/slurmctld.err" \
    || { _slurm_say "slurmctld failed: $(tail -n 5 "$base/log/slurmctld.err" "$base/log/slurmctld.log" 2>/dev/null)"; slurm_stop; return 1; }
  slurmd -f "$SLURM_CONF" </dev/null >/dev/null 2>"$base/log/slurmd.err" \
    || { _slurm_say "slurmd failed: $(tail -n 5 "$base/log/slurmd.err" "$base/log/slurmd.log" 2>/dev/null)"; slurm_stop; return 1; }

  # idle within 30 s; INVALID, DRAIN or DOWN after 3 s is an answer too
  state=""
  for ((i = 0; i < 300; i++)); do
    state=$(sinfo -h -n "$slurm_node" -o %T 2>/dev/null)
    [ "$state" = idle ] && break
    case "$state" in inval* | drain* | down*) [ "$i" -lt 30 ] || break ;; esac
    sleep 0.1
  done
  if [ "$state" != idle ]; then
    _slurm_say "node $slurm_node is '${state:-not known}', not idle: $(scontrol show node "$slurm_node" 2>/dev/null | grep -o 'Reason=.*')"
    _slurm_say "slurmctld.log: $(tail -n 5 "$base/log/slurmctld.log" 2>/dev/null)"
    _slurm_say "slurmd.log: $(tail -n 5 "$base/log/slurmd.log" 2>/dev/null)"
    slurm_stop
    return 1
  fi
  return 0
}

# slurm_stop: stops the cluster slurm_start started (no jobs left, no
# daemons, no steps). Safe to call twice, or when slurm_start failed.
slurm_stop() {
  [ -n "$slurm_base" ] || return 0
  _slurm_shutdown "$slurm_base"
  local sockets
  sockets=$(_slurm_sockets "$slurm_base")
  [ "$sockets" = "$slurm_base/run" ] || rm -rf "$sockets"
  return 0
}

# slurm_wait_job ID SECONDS: waits until the job (every task of an array)
# has a final state and prints it: COMPLETED, FAILED, CANCELLED, TIMEOUT,
# OUT_OF_MEMORY, ... — the distinct states of the tasks, space-separated
# and sorted, when they differ (e.g. "COMPLETED FAILED"). After SECONDS
# prints TIMEOUT(states seen) and returns 1; returns 1 with UNKNOWN when
# scontrol does not know the job.
slurm_wait_job() {
  local id="$1" seconds="$2" deadline out states state final
  deadline=$(( $(date +%s) + seconds ))
  while :; do
    if out=$(scontrol -o show job "$id" 2>&1); then
      states=$(grep -o 'JobState=[A-Z_]*' <<<"$out" | cut -d= -f2 | sort -u | tr '\n' ' ')
      states=${states% }
      final=1
      for state in $states; do
        case "$state" in
          COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | PREEMPTED | BOOT_FAIL | DEADLINE | OUT_OF_MEMORY) ;;
          *) final=0 ;;
        esac
      done
      if [ -n "$states" ] && [ "$final" = 1 ]; then
        echo "$states"
        return 0
      fi
    elif grep -q 'Invalid job id' <<<"$out"; then
      echo UNKNOWN
      return 1
    fi
    if [ "$(date +%s)" -ge "$deadline" ]; then
      echo "TIMEOUT(${states:-})"
      return 1
    fi
    sleep 0.2
  done
}
