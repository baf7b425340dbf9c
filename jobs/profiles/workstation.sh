# shellcheck shell=bash
# Machine profile: one workstation (sourced by the job scripts; jobs/run-workstation.sh takes it by default).
# Sets DIVCOLL_RANKS (default: every core, `nproc` without the OMP_* limits it honours), DIVCOLL_LAUNCH (the
# launcher's command line) and the Open MPI environment. Variables already set by the caller win. Needs
# DIVCOLL_ROOT.

# modules, if the machine has them: DIVCOLL_MODULES (default none)
if command -v module > /dev/null 2>&1 && [ -n "${DIVCOLL_MODULES:-}" ]; then
  for m in $DIVCOLL_MODULES; do
    module load "$m" || echo "profile: module $m could not be loaded" >&2
  done
fi

# root allowed, oversubscription allowed, no single-copy mechanism (containers) (TOOLCHAIN.md §1)
# shellcheck source=jobs/mpi-env.sh
source "$DIVCOLL_ROOT/jobs/mpi-env.sh"
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}

DIVCOLL_RANKS=${DIVCOLL_RANKS:-$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)}
DIVCOLL_LAUNCH=${DIVCOLL_LAUNCH:-mpirun -np $DIVCOLL_RANKS}
