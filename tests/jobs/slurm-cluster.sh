# shellcheck shell=bash
# A private single-node Slurm cluster on localhost for the job-script tests (sourced by slurm_test.sh and
# study_submit_test.sh): munged with its own socket and key, slurmctld and slurmd with a config in a
# temporary folder and two free ports, so that another Slurm on this machine (or another test) is left
# alone (TOOLCHAIN.md §4). The caller sets `deadline` (in SECONDS) and defines fail() and skip().
#   slurm_cluster_need          skips (77) when not root or a Slurm/munge command is missing
#   slurm_cluster_up W          starts the daemons in folder W (exports SLURM_CONF); skips if they will not start.
#                               SLURM_CLUSTER_AUTHINFO: more AuthInfo options (cred_expire=10: a requeued job
#                               starts again after 10 s, not 120)
#   slurm_cluster_down          cancels what is left in the queue, stops exactly the daemons started here
#                               and removes W (call it from an EXIT trap; SLURM_TEST_KEEP=1 keeps W)
#   slurm_wait_gone JOB SECS    waits until JOB has left the queue, fails after SECS (or at the deadline)
#   by SECS                     an end time SECS from now, or the deadline if that comes first

by() {
  local d=${deadline:?set deadline before sourcing slurm-cluster.sh}
  echo $((SECONDS + $1 < d ? SECONDS + $1 : d))
}

slurm_cluster_need() {
  export PATH=$PATH:/usr/sbin:/sbin
  [ "$(id -u)" = 0 ] || skip "not root (the test starts munged, slurmctld and slurmd as root)"
  local c
  for c in munged munge unmunge slurmctld slurmd sbatch squeue scancel sinfo scontrol mpirun h5dump; do
    command -v "$c" > /dev/null 2>&1 ||
      skip "$c is missing; install Slurm with jobs/install-deps.sh (slurmctld slurmd slurm-client munge)"
  done
}

# is process $1 running (not gone, not a zombie waiting for PID 1 to reap it)?
_slurm_running() {
  local st
  st=$(ps -o stat= -p "$1" 2> /dev/null) || return 1
  [[ $st != Z* ]]
}
# stop exactly the daemons started here, by the PIDs in their pid files (checking the process's name)
_slurm_stop_daemon() {
  local pidfile=$1 name=$2 pid
  [ -s "$pidfile" ] || return 0
  pid=$(cat "$pidfile")
  [ "$(cat "/proc/$pid/comm" 2> /dev/null)" = "$name" ] || return 0
  kill "$pid" 2> /dev/null || return 0
  for _ in $(seq 50); do
    _slurm_running "$pid" || return 0
    sleep 0.1
  done
  kill -9 "$pid" 2> /dev/null || true
}

slurm_cluster_down() {
  set +e
  [ -n "${_slurm_w:-}" ] || return 0
  local W=$_slurm_w
  # cancel what is left of the jobs (a failed test), so that no slurmstepd outlives slurmd
  if [ -s "$W/slurmctld.pid" ] && _slurm_running "$(cat "$W/slurmctld.pid")"; then
    local jobs
    jobs=$(squeue -h -o %i 2> /dev/null)
    if [ -n "$jobs" ]; then
      # shellcheck disable=SC2086
      scancel $jobs
      for _ in $(seq 100); do
        [ -z "$(squeue -h -o %i 2> /dev/null)" ] && break
        sleep 0.2
      done
    fi
  fi
  _slurm_stop_daemon "$W/slurmd.pid" slurmd
  _slurm_stop_daemon "$W/slurmctld.pid" slurmctld
  _slurm_stop_daemon "$W/munge/munged.pid" munged
  if [ "${SLURM_TEST_KEEP:-0}" = 1 ]; then echo "kept $W (SLURM_TEST_KEEP=1)"; else rm -rf "$W"; fi
  _slurm_w=
}

slurm_cluster_up() {
  local W=$1 t0=$SECONDS
  _slurm_w=$W
  chmod 711 "$W"  # munged wants its socket's folders searchable by all
  export SLURM_CONF=$W/slurm.conf
  echo "== munged (private socket and key)"
  mkdir -m 711 "$W/munge"
  mkdir -m 755 "$W/state" "$W/spool" "$W/log"
  mungekey -c -k "$W/munge/munge.key" 2> /dev/null ||
    { dd if=/dev/urandom of="$W/munge/munge.key" bs=1 count=1024 status=none && chmod 600 "$W/munge/munge.key"; }
  local sock=$W/munge/munge.socket
  munged --socket="$sock" --key-file="$W/munge/munge.key" --pid-file="$W/munge/munged.pid" \
    --log-file="$W/munge/munged.log" --seed-file="$W/munge/munged.seed" ||
    skip "munged would not start: $(tail -2 "$W/munge/munged.log" 2> /dev/null)"
  munge -n -S "$sock" | unmunge -S "$sock" > /dev/null || skip "munge credentials do not round-trip"

  echo "== slurmctld, slurmd (config in $W)"
  local host port node end
  host=$(hostname -s)
  # two free ports, so that a Slurm already on this machine is left alone
  for _ in $(seq 20); do
    port=$((20000 + RANDOM % 20000))
    if ! ss -Hltn 2> /dev/null | grep -qE ":($port|$((port + 1)))\b"; then break; fi
  done
  node=$(slurmd -C | head -1)  # NodeName=<host> CPUs=... RealMemory=...
  cat > "$SLURM_CONF" << EOC
ClusterName=divcolltest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$sock${SLURM_CLUSTER_AUTHINFO:+,$SLURM_CLUSTER_AUTHINFO}
MailProg=/bin/true
StateSaveLocation=$W/state
SlurmdSpoolDir=$W/spool
SlurmctldPidFile=$W/slurmctld.pid
SlurmdPidFile=$W/slurmd.pid
SlurmctldLogFile=$W/log/slurmctld.log
SlurmdLogFile=$W/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=pmix
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
ReturnToService=2
SchedulerType=sched/backfill
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOC
  slurmctld -f "$SLURM_CONF" || skip "slurmctld would not start: $(tail -3 "$W/log/slurmctld.log" 2> /dev/null)"
  slurmd -f "$SLURM_CONF" || skip "slurmd would not start: $(tail -3 "$W/log/slurmd.log" 2> /dev/null)"
  end=$(by 30)
  while [ "$SECONDS" -lt "$end" ] && [ "$(sinfo -h -o %t 2> /dev/null)" != idle ]; do sleep 0.2; done
  [ "$(sinfo -h -o %t 2> /dev/null)" = idle ] ||
    skip "the node did not become idle in 30 s: $(sinfo -h 2>&1 | head -2) $(tail -3 "$W/log/slurmd.log")"
  echo "cluster up in $((SECONDS - t0)) s: $(sinfo -h -o '%P %D %c %t')"
}

# waits until job $1 has left the queue (or fails after $2 seconds)
slurm_wait_gone() {
  local end
  end=$(by "$2")
  while [ -n "$(squeue -h -j "$1" -o %i 2> /dev/null)" ]; do
    [ "$SECONDS" -lt "$end" ] || fail "job $1 still queued or running after $2 s"
    sleep 0.2
  done
}
