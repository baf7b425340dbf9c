#!/usr/bin/env bash
# The driver's commit (mpi/driver.hpp): a job that dies exactly between writing a round's state and its round
# counter resumes to the run file of an uninterrupted run. The exit is placed by the program itself (the hidden
# hook DIVCOLL_DEBUG_EXIT_IN_COMMIT=<group>:<rounds done>: every rank flushes the run file, so what it holds
# on disk is the new state beside the old counter, then exits), not by time. Cases: the plain connectors plan,
# the extended one (keep_best, with its closing round), the graded stage's connectors (where a mismatch
# after kill and resume was once seen), and the deployment plans of the specialists and of a graded
# population (killed after their second environment; specialists.iterations=1, so the specialists'
# training never commits 2 under the same group), and both plans of the analysis stage (adversity after its
# second environment, familiarity after its first novel one). Usage: commit_kill_test.sh DIVCOLL SOURCE_DIR
set -euo pipefail
D=$1 SRC=$2
source "$SRC/jobs/mpi-env.sh"
# every rank must make the same HDF5 calls on the run file, reads included: checked at every checkpoint
# (io/h5.hpp Journal; a mismatch stops the run with each rank's calls)
export DIVCOLL_DEBUG_SYMMETRIC_IO=1
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
CFG=$SRC/configs/tiny.toml

check() {  # name  hook point  overrides...
  local name=$1 point=$2
  shift 2
  "$D" run "$CFG" "$@" --out "$W/$name-ref.h5" > "$W/$name-ref.log"
  local rc=0
  DIVCOLL_DEBUG_EXIT_IN_COMMIT=$point mpirun -np 2 "$D" run "$CFG" "$@" --out "$W/$name.h5" > "$W/$name-k.log" 2>&1 || rc=$?
  if ! grep -q "debug: exit between the state and the counter" "$W/$name-k.log" || [ "$rc" = 0 ]; then
    echo "FAILED: $name: the job did not exit at $point (exit $rc)"; cat "$W/$name-k.log"; exit 1
  fi
  grep -q "^done:" "$W/$name-k.log" && { echo "FAILED: $name: the job finished after the hook"; exit 1; }
  mpirun -np 3 "$D" run "$CFG" "$@" --out "$W/$name.h5" --resume > "$W/$name-r.log"
  grep -E "resum" "$W/$name-r.log" | head -3
  if ! "$D" compare "$W/$name-ref.h5" "$W/$name.h5"; then echo "FAILED: $name: the resumed run differs"; exit 1; fi
  echo "$name: passed"
}

check plain connectors:3 'run.stages=["agents","connectors"]' connectors.iterations=5
check keep_best connectors:3 'run.stages=["agents","connectors"]' connectors.iterations=5 connectors.keep_best=true \
  connectors.validation_pairs=3
check graded graded/same_shape/connectors:2 'run.stages=["agents","graded"]' connectors.iterations=3
check specialists_deploy specialists:2 'run.stages=["agents","specialists"]' specialists.iterations=1
check graded_deploy graded/same_shape:2 'run.stages=["agents","graded"]' connectors.iterations=1
ANALYSIS='run.stages=["agents","connectors","deploy","analysis"]'
check analysis_adversity analysis@dtw_envs_done:2 "$ANALYSIS" connectors.iterations=1
check analysis_familiarity analysis@familiarity_envs_done:1 "$ANALYSIS" connectors.iterations=1
echo "commit kill: passed"
