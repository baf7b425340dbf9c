# shellcheck shell=bash
# What the job scripts share (sourced by jobs/slurm/divcoll.sbatch, jobs/pbs/divcoll.pbs, the study's
# jobs/slurm/study-run.sbatch and jobs/pbs/study-run.pbs, and jobs/run-workstation.sh): load a machine profile, resolve the run's paths, and run
# `divcoll run CONFIG --out OUT --resume` so that it can be stopped and continued without losing work.
#
# Stopping. A killed run continues from its last checkpoint (OUT.ckpt, replaced at a commit every
# output.checkpoint_every rounds once output.checkpoint_interval_s has passed since the last copy, at every
# stage's end and on a stop) on --resume, bit-identically. divcoll itself stops right
# after its next checkpoint on SIGTERM/SIGINT/SIGUSR1 with exit 75 (mpirun forwards only SIGUSR1; on TERM it
# kills the ranks within a second, which loses at most the work since the last checkpoint). So on the
# "time is nearly up" signal (SIGUSR1: Slurm's --signal=B:USR1@T, or divcoll_arm_timer under PBS) the run
# (mpirun or divcoll) is sent SIGUSR1 and every rank stops together right after its next checkpoint (exit 75).
# If it has not ended after DIVCOLL_STOP_GRACE_S seconds (default 60) it gets SIGTERM (a second signal: it
# stops at once and keeps its last checkpoint), and SIGKILL 30 s later: at most the work since the last
# checkpoint is lost. Keep the grace well under the warning's lead (120 s): stopping and resubmitting take a
# few seconds more. SIGTERM/SIGINT (scancel, qdel, Ctrl-C) are passed to the run, which then ends without a
# continuation.

divcoll_log() { echo "[divcoll-job $(date -u +%FT%TZ)] $*"; }

# sets DIVCOLL_ROOT to the first folder holding this repository's jobs/lib/resumable-run.sh
divcoll_find_root() {
  local d
  for d in "$@"; do
    if [ -n "$d" ] && [ -f "$d/jobs/lib/resumable-run.sh" ]; then
      DIVCOLL_ROOT=$(cd "$d" && pwd)
      return 0
    fi
  done
  echo "divcoll-job: cannot find the divcoll repository (tried: $*); set DIVCOLL_ROOT" >&2
  return 1
}

# sources a machine profile: a name in jobs/profiles/ (workstation, generic-cluster) or a file's path. The
# profile sets DIVCOLL_RANKS, DIVCOLL_LAUNCH (the launcher's command line) and the MPI environment.
divcoll_load_profile() {
  local p=$1
  [ -f "$p" ] || p="$DIVCOLL_ROOT/jobs/profiles/$1.sh"
  if [ ! -f "$p" ]; then
    echo "divcoll-job: no profile '$1' (jobs/profiles/*.sh or a file)" >&2
    return 1
  fi
  # shellcheck source=/dev/null
  source "$p"
  divcoll_log "profile $p: $DIVCOLL_RANKS rank(s), launcher: $DIVCOLL_LAUNCH"
}

# an absolute path for CONFIG: as given, else relative to the repository
divcoll_config_path() {
  if [ -f "$1" ]; then
    realpath "$1"
  elif [ -f "$DIVCOLL_ROOT/$1" ]; then
    realpath "$DIVCOLL_ROOT/$1"
  else
    echo "divcoll-job: no config file $1" >&2
    return 1
  fi
}


# a sleep that a TERM trap can end (kill "$_divcoll_sp"), so that no orphaned sleep outlives the job
_divcoll_sleep() {
  sleep "$1" &
  _divcoll_sp=$!
  wait "$_divcoll_sp"
}

# trap handlers return 0 explicitly: a bare `return` in a handler gives the status of the interrupted `wait`
# (> 128), and under `set -e` that ends the job script
_divcoll_on_usr1() {
  if [ "${DIVCOLL_CAN_CONTINUE:-0}" != 1 ]; then
    divcoll_log "time-limit warning: no continuation can follow (${DIVCOLL_NO_CONTINUE_WHY:-no scheduler}); the run goes on until the limit"
    return 0
  fi
  if [ -n "$_divcoll_stopper" ]; then
    return 0
  fi
  DIVCOLL_STOPPED=1
  local grace=${DIVCOLL_STOP_GRACE_S:-60}
  divcoll_log "time-limit warning: stopping the run after its next checkpoint (at most ${grace} s)"
  (
    # ended early (the run stopped or finished first): take the sleep along; a second warning changes nothing
    trap 'kill "$_divcoll_sp" 2>/dev/null; exit 0' TERM
    trap '' USR1
    end=$((SECONDS + grace))
    # divcoll stops itself right after its next checkpoint on SIGUSR1 (mpirun forwards it to every rank); its
    # ranks act on it once they have taken the run's lock (OUT.lock, written after the handlers are installed)
    # — before that, SIGUSR1's default action would end them, so wait for a lock file of this run
    while [ "$SECONDS" -lt "$end" ] && kill -0 "$_divcoll_pid" 2>/dev/null &&
      [ "$(stat -c %Y "$_divcoll_out.lock" 2>/dev/null || echo 0)" -lt "$_divcoll_started" ]; do
      _divcoll_sleep 0.2
    done
    kill -0 "$_divcoll_pid" 2>/dev/null || exit 0
    [ "$SECONDS" -lt "$end" ] && kill -USR1 "$_divcoll_pid" 2>/dev/null
    while [ "$SECONDS" -lt "$end" ] && kill -0 "$_divcoll_pid" 2>/dev/null; do _divcoll_sleep 0.5; done
    kill -0 "$_divcoll_pid" 2>/dev/null || exit 0
    divcoll_log "no checkpoint within ${grace} s: stopping anyway (the run continues from the previous one)"
    kill -TERM "$_divcoll_pid" 2>/dev/null || exit 0
    _divcoll_sleep 30
    kill -KILL "$_divcoll_pid" 2>/dev/null || true
  ) &
  _divcoll_stopper=$!
  return 0
}

_divcoll_on_term() {
  divcoll_log "SIGTERM/SIGINT: passing it to the run (no continuation)"
  DIVCOLL_STOPPED=0
  DIVCOLL_CAN_CONTINUE=0
  kill -TERM "$_divcoll_pid" 2>/dev/null || true
  return 0
}

# divcoll_run_resumable CONFIG OUT [section.key=value ...]: runs
#   $DIVCOLL_LAUNCH $DIVCOLL_BIN run CONFIG --out OUT --resume [overrides]
# and returns its exit status. Sets DIVCOLL_STOPPED=1 if it was stopped for a continuation (SIGUSR1 while
# DIVCOLL_CAN_CONTINUE=1), 0 otherwise.
divcoll_run_resumable() {
  local config=$1 out=$2
  shift 2
  divcoll_launch_resumable "$out" run "$config" --out "$out" --resume "$@"
}

# divcoll_launch_resumable OUT ARGS...: the same for any divcoll command that writes the run file OUT
# (`study STUDY --out DIR --resume --run K` writes DIR/<variant>/seed<k>.h5): $DIVCOLL_LAUNCH $DIVCOLL_BIN ARGS
divcoll_launch_resumable() {
  local out=$1 rc=0
  shift
  local -a launch
  read -ra launch <<< "${DIVCOLL_LAUNCH:-}"
  _divcoll_out=$out
  _divcoll_stopper=
  # shellcheck disable=SC2034  # read by the job scripts
  DIVCOLL_STOPPED=0
  divcoll_log "${launch[*]} $DIVCOLL_BIN $*"
  _divcoll_started=$(date +%s)
  "${launch[@]}" "$DIVCOLL_BIN" "$@" &
  _divcoll_pid=$!
  trap _divcoll_on_usr1 USR1
  trap _divcoll_on_term TERM INT
  # a warning that came before the run started: job scripts begin with
  #   trap '_divcoll_usr1_pending=1' USR1
  # (SIGUSR1's default action would end the job script)
  if [ "${_divcoll_usr1_pending:-0}" = 1 ]; then
    _divcoll_usr1_pending=0
    _divcoll_on_usr1
  fi
  # a trapped signal ends `wait` early (status > 128) while the run goes on: wait again
  while :; do
    rc=0
    wait "$_divcoll_pid" || rc=$?
    { [ "$rc" -le 128 ] || ! kill -0 "$_divcoll_pid" 2>/dev/null; } && break
  done
  trap - TERM INT
  trap 'divcoll_log "time-limit warning after the run ended: ignored"' USR1
  if [ -n "$_divcoll_stopper" ]; then
    kill "$_divcoll_stopper" 2>/dev/null || true
    wait "$_divcoll_stopper" 2>/dev/null || true
  fi
  if [ "$DIVCOLL_STOPPED" = 1 ] && [ "$rc" = 75 ]; then
    divcoll_log "checkpoint written: the run stopped right after it (status 75)"
  fi
  divcoll_log "the run ended with status $rc"
  return "$rc"
}

# divcoll_arm_timer SECONDS: sends SIGUSR1 to this shell after SECONDS (for schedulers without Slurm's
# --signal); divcoll_disarm_timer cancels it
divcoll_arm_timer() {
  local s=$1 me=$$
  if [ "$s" -le 0 ]; then
    # at once: taken as arrived, without a signal. A signal sent now would reach this shell while it parses its
    # next command substitution, and bash 5.2 then runs the trap inside that parse ("trap: line 2: unexpected
    # EOF while looking for matching `)'", which ended a job of the PBS test)
    _divcoll_usr1_pending=1
    divcoll_log "time-limit warning armed: SIGUSR1 in 0 s (taken as arrived)"
    return 0
  fi
  (
    trap 'kill "$_divcoll_sp" 2>/dev/null; exit 0' TERM
    trap '' USR1
    _divcoll_sleep "$s" && kill -USR1 "$me"
  ) &
  _divcoll_timer=$!
  divcoll_log "time-limit warning armed: SIGUSR1 in $s s"
}
divcoll_disarm_timer() {
  if [ -n "${_divcoll_timer:-}" ]; then
    kill "$_divcoll_timer" 2>/dev/null || true
    wait "$_divcoll_timer" 2>/dev/null || true
    _divcoll_timer=
  fi
}

# the environment of a resubmission: no variables of this job's allocation (SLURM_*, except the
# scheduler's own configuration), so that the new job sees only its own
divcoll_clean_env_args() {
  local v
  for v in $(compgen -A variable SLURM_); do
    case $v in
      SLURM_CONF | SLURM_CLUSTERS) ;;
      *) printf '%s\n' -u "$v" ;;
    esac
  done
}
