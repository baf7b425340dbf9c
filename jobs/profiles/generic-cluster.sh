# shellcheck shell=bash
# Machine profile: a cluster node under Slurm or PBS (sourced by jobs/slurm/divcoll.sbatch and
# jobs/pbs/divcoll.pbs, which take it by default). Copy it to jobs/profiles/<machine>.sh for a machine whose
# module names or launcher differ, and submit with DIVCOLL_PROFILE=<machine>.
# Sets DIVCOLL_RANKS (the allocation's), DIVCOLL_LAUNCH (the launcher's command line) and the MPI environment.
# Variables already set by the caller win.

# modules, if the machine has them: DIVCOLL_MODULES (default "openmpi hdf5"; set it empty to load none). The
# build must use the same MPI and parallel HDF5 that are loaded here.
if command -v module > /dev/null 2>&1; then
  for m in ${DIVCOLL_MODULES-openmpi hdf5}; do
    module load "$m" || echo "profile: module $m could not be loaded" >&2
  done
fi

if [ -n "${SLURM_JOB_ID:-}" ]; then
  # Slurm: direct launch with PMIx (Debian's Open MPI has no PMI2 support; TOOLCHAIN.md §4)
  DIVCOLL_RANKS=${DIVCOLL_RANKS:-${SLURM_NTASKS:-1}}
  DIVCOLL_LAUNCH=${DIVCOLL_LAUNCH:-srun --mpi=${DIVCOLL_SRUN_MPI:-pmix} -n $DIVCOLL_RANKS}
elif [ -n "${PBS_NODEFILE:-}" ]; then
  # PBS: Open MPI without TM support needs the node file as its host file (one line per rank)
  DIVCOLL_RANKS=${DIVCOLL_RANKS:-$(wc -l < "$PBS_NODEFILE")}
  DIVCOLL_LAUNCH=${DIVCOLL_LAUNCH:-mpirun -np $DIVCOLL_RANKS --hostfile $PBS_NODEFILE}
else
  DIVCOLL_RANKS=${DIVCOLL_RANKS:-$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)}
  DIVCOLL_LAUNCH=${DIVCOLL_LAUNCH:-mpirun -np $DIVCOLL_RANKS}
fi

# Open MPI refuses to run as root unless told (TOOLCHAIN.md §1); MPICH ignores these
if [ "$(id -u)" = 0 ]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
# HDF5 1.10's file locking fails on some NFS/Lustre mounts (TOOLCHAIN.md §2); one thread per rank
export HDF5_USE_FILE_LOCKING=${HDF5_USE_FILE_LOCKING:-FALSE}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
