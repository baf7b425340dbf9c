#!/usr/bin/env bash
# jobs/slurm/divcoll.sbatch on a real Slurm: a private single-node cluster on localhost (munged, slurmctld,
# slurmd with a config in a temporary folder; TOOLCHAIN.md §4), a run of tiny.toml (made longer by overrides)
# whose job gets the time-limit warning (SIGUSR1 to the batch shell, as --signal=B:USR1@120 sends it),
# stops after a checkpoint and resubmits itself; the continuation ignores its own warning (no
# resubmissions left) and completes the run, which must equal a plain mpirun run of the same config.
# Usage: slurm_test.sh DIVCOLL SOURCE_DIR. Exit 77 (skipped) when Slurm is not installed or will not start.
set -euo pipefail
D=$1 SRC=$2
OVR=(agents.population=10 agents.generations=12 agents.epochs=5 agents.episode_steps=1000)
t_start=$SECONDS
# every wait ends by this deadline, well inside ctest's TIMEOUT (660 s, which would kill the test without its
# cleanup). The waits are bounds for a hung job, not timings: generous, so that a loaded machine passes
deadline=$((SECONDS + ${SLURM_TEST_BUDGET_S:-600}))

skip() {
  echo "slurm test SKIPPED: $*"
  exit 77
}
fail() {
  echo "slurm test FAILED: $*"
  for f in "$W"/*.out "$W/log/slurmctld.log" "$W/log/slurmd.log"; do
    [ -f "$f" ] && { echo "---- $f (last 40 lines)"; tail -40 "$f"; }
  done
  exit 1
}
# shellcheck source=tests/jobs/slurm-cluster.sh
source "$SRC/tests/jobs/slurm-cluster.sh"
slurm_cluster_need
W=$(mktemp -d)
trap slurm_cluster_down EXIT
trap 'exit 1' TERM INT HUP
slurm_cluster_up "$W"

echo "== reference: plain mpirun, 2 ranks"
(
  # shellcheck source=jobs/mpi-env.sh
  source "$SRC/jobs/mpi-env.sh"
  timeout "$((deadline - SECONDS))" mpirun -np 2 "$D" run "$SRC/configs/tiny.toml" "${OVR[@]}" --out "$W/ref.h5" > "$W/ref.log" 2>&1
) || { cat "$W/ref.log"; fail "the reference run failed"; }

echo "== sbatch jobs/slurm/divcoll.sbatch"
cd "$W"
export DIVCOLL_BIN=$D DIVCOLL_PROFILE=generic-cluster DIVCOLL_MAX_RESUBMITS=1 DIVCOLL_STOP_GRACE_S=60
script=$SRC/jobs/slurm/divcoll.sbatch
opts=(--ntasks=2 --time=10 --job-name=divcoll-test)
sbatch --test-only "${opts[@]}" "$script" > /dev/null 2>&1 ||
  fail "sbatch --test-only refuses the job: $(sbatch --test-only "${opts[@]}" "$script" 2>&1)"
j1=$(sbatch --parsable "${opts[@]}" "$script" "$SRC/configs/tiny.toml" "$W/run.h5" "${OVR[@]}")
j1=${j1%%;*}
echo "job $j1 submitted"

# the time-limit warning as Slurm sends it with --signal=B:USR1@120: SIGUSR1 to the batch shell only
warn() { scancel --batch --signal=USR1 "$1"; }

# the first checkpoint exists: the run is under way
end=$(by 240)
until [ -f "$W/run.h5.ckpt" ]; do
  [ "$SECONDS" -lt "$end" ] || fail "no checkpoint after $((SECONDS - t_start)) s of the test"
  [ -n "$(squeue -h -j "$j1" -o %i)" ] || fail "job $j1 ended before its first checkpoint"
  sleep 0.1
done
warn "$j1"
echo "job $j1: time-limit warning sent after the first checkpoint"
slurm_wait_gone "$j1" 240
j2=$(sed -n 's/.*resubmitted as job \([0-9]*\).*/\1/p' "$W/divcoll-test-$j1.out")
[ -n "$j2" ] || fail "job $j1 did not resubmit itself"
echo "job $j1 stopped and resubmitted itself as job $j2"

# the continuation has no resubmission left: it logs its warning and runs on
end=$(by 180)
until grep -q -- "--resume" "$W/divcoll-test-$j2.out" 2> /dev/null; do
  [ "$SECONDS" -lt "$end" ] || fail "job $j2 did not start the run in time"
  sleep 0.2
done
warn "$j2"  # held until the run has started if it comes earlier (the job script traps it from its first line)
slurm_wait_gone "$j2" 360
[ -z "$(squeue -h -o %i)" ] || fail "jobs left in the queue: $(squeue -h)"

echo "== checks"
for j in "$j1" "$j2"; do
  info=$(scontrol show job -o "$j")
  state=$(grep -o ' JobState=[^ ]*' <<< "$info")$(grep -o ' ExitCode=[^ ]*' <<< "$info")
  [ "$state" = " JobState=COMPLETED ExitCode=0:0" ] || fail "job $j:$state"
done
o1=$W/divcoll-test-$j1.out o2=$W/divcoll-test-$j2.out
grep -q "stopping the run after its next checkpoint" "$o1" || fail "job $j1 did not act on the warning"
grep -q "checkpoint written: the run stopped right after it" "$o1" || fail "job $j1 did not stop at a checkpoint"
! grep -q "run complete" "$o1" || fail "the warning came too late: job $j1 completed the run"
grep -q "resuming" "$o2" || fail "job $j2 did not resume the run"
grep -q "no continuation can follow" "$o2" || fail "job $j2 did not log its ignored warning"
! grep -q "resubmitted" "$o2" || fail "job $j2 resubmitted itself beyond DIVCOLL_MAX_RESUBMITS=1"
grep -q "run complete" "$o2" || fail "job $j2 did not complete the run"
for g in agents connectors deploy specialists scaling graded; do
  h5dump -a "/$g/status" "$W/run.h5" | grep -q '"complete"' || fail "stage $g is not complete in the run file"
done
h5dump -a /end_time "$W/run.h5" > /dev/null 2>&1 || fail "the run file has no end_time"
[ ! -e "$W/run.h5.ckpt" ] || fail "the checkpoint of the completed run is still there"
"$D" compare "$W/ref.h5" "$W/run.h5" || fail "the Slurm run differs from the plain mpirun run"
echo "slurm: passed in $((SECONDS - t_start)) s (job $j1 stopped after a checkpoint, job $j2 resumed and completed)"
