#!/usr/bin/env bash
# The job scripts without a scheduler (Debian has no PBS; TOOLCHAIN.md §4):
#  1. `bash -n` and shellcheck over every script in jobs/ and tests/jobs/;
#  2. jobs/pbs/divcoll.pbs run as PBS would run it (PBS_NODEFILE listing localhost twice, PBS_O_WORKDIR,
#     started from /) on tiny.toml: a complete run file;
#  3. the walltime path: a PBS_WALLTIME that arms the script's own timer 1 s after the start (SIGUSR1), a
#     stand-in qsub that records what it is given; the job must stop after a checkpoint and resubmit itself
#     (qsub -V -W depend=afterany:<job>); the resubmitted job, run here with the variables qsub -V passes,
#     ignores its own warning (no resubmissions left) and completes the run, which must equal a plain
#     mpirun run of the same config;
#  4. `divcoll study --submit pbs` with a stand-in qsub (one array per level of reuse, the report job after
#     them), one subjob run as PBS runs it (a complete run file), and a subjob whose base has not ended
#     (it submits itself again after the base's job).
# Usage: pbs_check.sh DIVCOLL SOURCE_DIR. Exit 77 (skipped) if shellcheck is missing (the rest still runs).
set -euo pipefail
D=$1 SRC=$2
OVR=(agents.population=10 agents.generations=12 agents.epochs=5 agents.episode_steps=1000)
# every rank must make the same HDF5 calls on the run file, reads included: checked at every checkpoint
# (io/h5.hpp Journal; a mismatch stops the run with each rank's calls)
export DIVCOLL_DEBUG_SYMMETRIC_IO=1
t_start=$SECONDS
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
fail() {
  echo "pbs check FAILED: $*"
  for f in "$W"/*.log; do
    [ -f "$f" ] && { echo "---- $f (last 30 lines)"; tail -30 "$f"; }
  done
  for f in "$W"/*.stacks; do
    [ -f "$f" ] && { echo "---- $f (every divcoll process of a job that outlived its watchdog)"; cat "$f"; }
  done
  exit 1
}
# the stack of every thread of every divcoll process still running (gdb, else the kernel's wait channel):
# what a hang leaves for whoever reads the failure
dump_stacks() {
  local p
  for p in $(pgrep -x divcoll || true); do
    grep -qF "$W" "/proc/$p/cmdline" 2> /dev/null || continue  # this check's ranks only
    echo "== pid $p: $(tr '\0' ' ' < "/proc/$p/cmdline" 2>/dev/null)"
    if command -v gdb > /dev/null 2>&1; then
      timeout 30 gdb -p "$p" -batch -ex "thread apply all bt" 2>&1 | grep -E '^(Thread|#)' || true
    else
      for t in /proc/"$p"/task/*; do echo "thread ${t##*/}: $(cat "$t/wchan" 2>/dev/null)"; done
    fi
  done
}

echo "== bash -n, shellcheck"
cd "$SRC"
mapfile -t scripts < <(find jobs tests/jobs -type f \( -name '*.sh' -o -name '*.sbatch' -o -name '*.pbs' \) | sort)
for s in "${scripts[@]}"; do
  bash -n "$s" || fail "bash -n $s"
done
echo "bash -n: ${#scripts[@]} scripts ok"
have_shellcheck=1
if command -v shellcheck > /dev/null 2>&1; then
  # -s bash: sourced files without a shebang (jobs/mpi-env.sh); -x: follow `source` (paths from here)
  shellcheck -x -s bash "${scripts[@]}" || fail "shellcheck found problems (above)"
  echo "shellcheck: ${#scripts[@]} scripts clean"
else
  have_shellcheck=0
  echo "shellcheck is missing (jobs/install-deps.sh installs it); the other checks still run"
fi

# a PBS job's environment: node file, submit folder, job id; never a Slurm job's
printf 'localhost\nlocalhost\n' > "$W/nodefile"
mkdir "$W/bin"
cat > "$W/bin/qsub" << EOF
#!/usr/bin/env bash
# stand-in qsub: records its arguments and the variables the resubmitted job needs
printf '%s\n' "\$@" > "$W/qsub.args"
printf '%s\n' "CONFIG=\$CONFIG" "OUT=\$OUT" "DIVCOLL_OVERRIDES=\$DIVCOLL_OVERRIDES" \\
  "DIVCOLL_RESUBMIT_COUNT=\$DIVCOLL_RESUBMIT_COUNT" > "$W/qsub.env"
echo 1002.fake
EOF
chmod +x "$W/bin/qsub"
pbs_job() {  # pbs_job LOG VAR=VALUE...: the PBS script as PBS runs it (from /, a copy-independent path)
  local log=$1 rc=0
  shift
  # a watchdog: a job still running after 100 s (a tiny run takes seconds) has its ranks' stacks recorded
  # before `timeout` ends it at 120 s
  (for _ in $(seq 100); do [ -e "$W/$log.done" ] && exit 0; sleep 1; done; dump_stacks > "$W/$log.stacks") &
  local dog=$!
  (cd / && env -u SLURM_JOB_ID PATH="$W/bin:$PATH" PBS_NODEFILE="$W/nodefile" PBS_O_WORKDIR="$W" \
    PBS_JOBNAME=divcoll-pbs DIVCOLL_BIN="$D" DIVCOLL_PROFILE=generic-cluster "$@" \
    timeout 120 bash "$SRC/jobs/pbs/divcoll.pbs") > "$W/$log" 2>&1 || rc=$?
  touch "$W/$log.done"
  wait "$dog" || true
  return "$rc"
}
complete_run_file() {  # every stage complete, an end time, no checkpoint left
  local g
  for g in agents connectors deploy specialists scaling graded; do
    h5dump -a "/$g/status" "$1" | grep -q '"complete"' || fail "$1: stage $g is not complete"
  done
  h5dump -a /end_time "$1" > /dev/null 2>&1 || fail "$1 has no end_time"
  [ ! -e "$1.ckpt" ] || fail "$1: the checkpoint of a completed run is still there"
}

echo "== jobs/pbs/divcoll.pbs, tiny.toml, 2 ranks from PBS_NODEFILE"
pbs_job pbs-tiny.log PBS_JOBID=1000.fake CONFIG=configs/tiny.toml OUT=tiny.h5 ||
  fail "the PBS script failed on tiny.toml"
grep -q "launcher: mpirun -np 2 --hostfile $W/nodefile" "$W/pbs-tiny.log" || fail "not launched from PBS_NODEFILE"
grep -q "run on 2 rank(s)" "$W/pbs-tiny.log" || fail "not 2 ranks"
complete_run_file "$W/tiny.h5"
echo "tiny.toml: complete run file $W/tiny.h5 (OUT relative to PBS_O_WORKDIR)"

echo "== walltime warning, stop after a checkpoint, resubmission"
(
  # shellcheck source=jobs/mpi-env.sh
  source "$SRC/jobs/mpi-env.sh"
  timeout 120 mpirun -np 2 "$D" run "$SRC/configs/tiny.toml" "${OVR[@]}" --out "$W/ref.h5" > "$W/ref.log" 2>&1
) || fail "the reference run failed"
walltime=(PBS_WALLTIME=121 DIVCOLL_STOP_BEFORE_S=120 DIVCOLL_MAX_RESUBMITS=1)
pbs_job pbs-1.log PBS_JOBID=1001.fake "${walltime[@]}" CONFIG="$SRC/configs/tiny.toml" OUT="$W/run.h5" \
  DIVCOLL_OVERRIDES="${OVR[*]}" || fail "job 1001 failed"
grep -q "time-limit warning armed: SIGUSR1 in 1 s" "$W/pbs-1.log" || fail "job 1001 armed no timer"
grep -q "checkpoint written: the run stopped right after it" "$W/pbs-1.log" || fail "job 1001 did not stop at a checkpoint"
grep -q "resubmitted as job 1002.fake" "$W/pbs-1.log" || fail "job 1001 did not resubmit itself"
! h5dump -a /end_time "$W/run.h5" > /dev/null 2>&1 || fail "the warning came too late: job 1001 completed the run"
for a in -V "depend=afterany:1001.fake" "walltime=0:02:01" divcoll-pbs "$SRC/jobs/pbs/divcoll.pbs"; do
  grep -qxF -- "$a" "$W/qsub.args" || fail "qsub was not given $a: $(tr '\n' ' ' < "$W/qsub.args")"
done
grep -qxF "DIVCOLL_RESUBMIT_COUNT=1" "$W/qsub.env" || fail "resubmission count: $(cat "$W/qsub.env")"
echo "job 1001 stopped after a checkpoint and ran: qsub $(tr '\n' ' ' < "$W/qsub.args")"
rm "$W/qsub.args"

mapfile -t passed < "$W/qsub.env"
# job 1002 may take under a second: a walltime equal to the lead makes its warning come at once, so that it
# always arrives while the job runs (before the run starts it is held and handled when the run starts)
pbs_job pbs-2.log PBS_JOBID=1002.fake PBS_WALLTIME=120 DIVCOLL_STOP_BEFORE_S=120 DIVCOLL_MAX_RESUBMITS=1 \
  "${passed[@]}" || fail "job 1002 failed"
grep -q "time-limit warning armed: SIGUSR1 in 0 s" "$W/pbs-2.log" || fail "job 1002 armed no immediate timer"
grep -q "resuming" "$W/pbs-2.log" || fail "job 1002 did not resume the run"
grep -q "no continuation can follow (resubmission 1 of at most 1)" "$W/pbs-2.log" ||
  fail "job 1002 did not log its ignored warning"
[ ! -e "$W/qsub.args" ] || fail "job 1002 resubmitted itself beyond DIVCOLL_MAX_RESUBMITS=1"
complete_run_file "$W/run.h5"
"$D" compare "$W/ref.h5" "$W/run.h5" || fail "the stopped and resubmitted run differs from the plain mpirun run"
echo "job 1002 resumed and completed the run: identical to the plain run"

echo "== a study submitted to PBS (stand-in qsub), one subjob run as PBS runs it"
mkdir "$W/sbin"
cat > "$W/sbin/qsub" << EOF
#!/usr/bin/env bash
# stand-in qsub: one line of arguments per call, job ids 3000.fake, 3001.fake, ... (arrays: 3000[].fake)
n=\$(wc -l < "$W/study-qsub.log" 2> /dev/null || echo 0)
printf '%s\n' "\$*" >> "$W/study-qsub.log"
case " \$* " in *" -J "*) echo "\$((3000 + n))[].fake" ;; *) echo "\$((3000 + n)).fake" ;; esac
EOF
chmod +x "$W/sbin/qsub"
S=$W/pbs-study
PATH="$W/sbin:$PATH" "$D" study "$SRC/configs/studies/tiny.toml" --out "$S" --submit pbs --ranks-per-run 2 \
  --max-parallel 2 --dry-run > "$W/pbs-dry.log" 2>&1 || fail "the PBS dry run failed"
{ [ ! -e "$S" ] && [ ! -e "$W/study-qsub.log" ]; } || fail "the PBS dry run wrote or submitted something"
PATH="$W/sbin:$PATH" "$D" study "$SRC/configs/studies/tiny.toml" --out "$S" --submit pbs --ranks-per-run 2 \
  --max-parallel 2 -- -A myproject > "$W/pbs-submit.log" 2>&1 || fail "the PBS submission failed"
cat "$W/pbs-submit.log"
mapfile -t calls < "$W/study-qsub.log"
[ "${#calls[@]}" = 3 ] || fail "not 3 qsub calls (level 0, level 1, report): ${calls[*]}"
[[ ${calls[0]} == *"select=1:ncpus=2:mpiprocs=2"*"-J 1-2%2 "*"DIVCOLL_STUDY_LEVEL_FILE=$S/jobs/level-0.runs"*"-A myproject"* ]] ||
  fail "level 0: qsub ${calls[0]}"
[[ ${calls[1]} == *"-J 1-2%2 "*"depend=afterok:3000[].fake"* ]] || fail "level 1: qsub ${calls[1]}"
[[ ${calls[2]} == *"DIVCOLL_STUDY_REPORT=1"*"depend=afterany:3000[].fake:3001[].fake"* ]] || fail "report: qsub ${calls[2]}"
{ [ "$(cat "$S/jobs/level-0.runs")" = "$(printf '1\n3')" ] && [ "$(cat "$S/jobs/level-1.runs")" = "$(printf '2\n4')" ]; } ||
  fail "level files: $(cat "$S"/jobs/level-*.runs)"
# the job's environment as qsub -v gives it (the level-0 array's variables)
IFS=, read -ra vars <<< "$(sed -n 's/.* -v \([^ ]*\) .*/\1/p' <<< "${calls[0]}")"
study_job() {  # study_job LOG VAR=VALUE...: jobs/pbs/study-run.pbs as PBS runs it
  local log=$1 rc=0
  shift
  (cd / && env -u SLURM_JOB_ID PATH="$W/sbin:$PATH" PBS_NODEFILE="$W/nodefile" PBS_O_WORKDIR="$W" \
    PBS_JOBNAME=divcoll-tiny DIVCOLL_PROFILE=generic-cluster "${vars[@]}" "$@" \
    timeout 120 bash "$SRC/jobs/pbs/study-run.pbs") > "$W/$log" 2>&1 || rc=$?
  return "$rc"
}
# subjob 1 of level 0: run 1 (baseline seed 1) on the 2 ranks of the node file
study_job pbs-study-1.log PBS_JOBID='3000[1].fake' PBS_ARRAY_INDEX=1 || fail "subjob 3000[1] failed"
grep -q "launcher: mpirun -np 2 --hostfile $W/nodefile" "$W/pbs-study-1.log" || fail "subjob 1 not launched from PBS_NODEFILE"
grep -q "run complete: baseline/seed1.h5" "$W/pbs-study-1.log" || fail "subjob 1 did not complete run 1"
for g in agents connectors deploy analysis; do
  h5dump -a "/$g/status" "$S/baseline/seed1.h5" | grep -q '"complete"' || fail "run 1: stage $g is not complete"
done
grep -q "state=complete" "$S/baseline/seed1.job" || fail "subjob 1 did not record its run complete"
# subjob 2 of level 1 (run 4) before its base (run 3) has ended: it goes again after the base's job
study_job pbs-study-4.log PBS_JOBID='3001[2].fake' PBS_ARRAY_INDEX=2 DIVCOLL_STUDY_LEVEL_FILE="$S/jobs/level-1.runs" ||
  fail "subjob 3001[2] failed"
grep -qF "baseline/seed2.h5 has not ended: this run goes again after job 3000[].fake" "$W/pbs-study-4.log" ||
  fail "run 4 before its base: $(tail -5 "$W/pbs-study-4.log")"
[[ $(tail -1 "$W/study-qsub.log") == "-V -W depend=afterok:3000[].fake -N divcoll-tiny "*"/jobs/pbs/study-run.pbs" ]] ||
  fail "run 4's resubmission: qsub $(tail -1 "$W/study-qsub.log")"
[ ! -e "$S/long_deploy/seed2.h5" ] || fail "run 4 started without its base"
echo "PBS study: levels and dependencies submitted; subjob 1 computed run 1; run 4 waits for its base's job"

if [ "$have_shellcheck" = 0 ]; then
  echo "pbs checks SKIPPED in part: shellcheck is missing"
  exit 77
fi
echo "pbs checks: passed in $((SECONDS - t_start)) s"
