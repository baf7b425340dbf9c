# shellcheck shell=bash
# What the study's job scripts share (sourced by jobs/study-submit.sh, jobs/slurm/study-run.sbatch and
# jobs/pbs/study-run.pbs, after jobs/lib/resumable-run.sh).
#
# DIR/jobs/runs.tsv (written by `divcoll study --submit`): one line per run to compute, tab-separated:
#   number  path  number-of-the-run-it-waits-for (0: none)  stages  reused-run-path (-: none)
# DIR/<variant>/seed<k>.job: what the jobs did with a run, one key=value per line, appended (the last value of
# a key holds; `divcoll study DIR --status` reads it): scheduler, job, state (queued, running, requeued,
# resubmitted, complete, failed), log, rc, and started/ended (seconds since 1970) at every start and end.

# the field $2 (1-based) of run number $1 in runs file $3
study_field() {
  awk -F '\t' -v k="$1" -v f="$2" '$1 == k { print $f; exit }' "$3"
}

# appends key=value lines to the job file of run path $1 (relative to DIVCOLL_STUDY_DIR)
study_record() {
  local f=$DIVCOLL_STUDY_DIR/${1%.h5}.job
  shift
  mkdir -p "$(dirname "$f")"
  printf '%s\n' "$@" >> "$f"
}

# the last value of key $2 in the job file of run path $1
study_recorded() {
  local f=$DIVCOLL_STUDY_DIR/${1%.h5}.job
  [ -f "$f" ] || return 0
  sed -n "s/^$2=//p" "$f" | tail -1
}

# study_run_task K JOB LOG: computes run K of the study (DIVCOLL_STUDY, DIVCOLL_STUDY_DIR) with the resumable
# launcher, recording its job's states; returns divcoll's status (75: stopped for a continuation, 3: the run
# it reuses has not ended)
study_run_task() {
  local k=$1 job=$2 log=$3 path rc=0
  path=$(study_field "$k" 2 "$DIVCOLL_STUDY_DIR/jobs/runs.tsv")
  [ -n "$path" ] || { divcoll_log "run $k is not in $DIVCOLL_STUDY_DIR/jobs/runs.tsv"; return 2; }
  # shellcheck disable=SC2034  # read by the job scripts
  STUDY_RUN_PATH=$path
  mkdir -p "$DIVCOLL_STUDY_DIR/$(dirname "$path")"
  study_record "$path" "job=$job" "log=$log" "state=running" "started=$(date +%s.%N)"
  divcoll_log "study run $k: $path (job $job)"
  # by its path, not its number: a study file that gained variants since the submission numbers its runs anew
  divcoll_launch_resumable "$DIVCOLL_STUDY_DIR/$path" study "$DIVCOLL_STUDY" --out "$DIVCOLL_STUDY_DIR" --resume \
    --run "$path" || rc=$?
  local state=failed
  if [ "$rc" = 0 ]; then
    state=complete
  elif [ "$DIVCOLL_STOPPED" = 1 ] && [ "$rc" = 75 ]; then
    state=stopped
  elif [ "$rc" = 3 ]; then
    state=waiting
  fi
  study_record "$path" "state=$state" "rc=$rc" "ended=$(date +%s.%N)"
  return "$rc"
}

# the report job: every run's state, then the summaries and the robustness page (divcoll report DIR)
study_report_task() {
  local rc=0 status
  divcoll_log "study $DIVCOLL_STUDY_DIR: every run job has ended"
  status=$("$DIVCOLL_BIN" study "$DIVCOLL_STUDY_DIR" --status 2>&1) || rc=$?
  echo "$status"
  if [ "$rc" != 0 ] || ! grep -q "the study is complete" <<< "$status"; then
    divcoll_log "not every run is complete (above): no report; fix what failed and submit the study again (the same command)"
    return 1
  fi
  "$DIVCOLL_BIN" report "$DIVCOLL_STUDY_DIR" || rc=$?
  divcoll_log "divcoll report $DIVCOLL_STUDY_DIR ended with status $rc"
  return "$rc"
}
