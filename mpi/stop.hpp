// clean stops. SIGTERM, SIGINT and SIGUSR1 ask the run to stop right after its next checkpoint:
// every rank learns of it at the next commit of a stage's state (an allreduce), which then copies the run
// file to its checkpoint whatever output.checkpoint_interval_s says; the run file is closed, the lock dropped, and
// the run exits with kStoppedExit; `--resume` continues it. If no checkpoint comes within
// run.stop_grace_s seconds, or a second signal arrives, the process ends at once with 128 + signal (the
// last checkpoint is kept: it is replaced only by a complete, verified copy).
//
// Under mpirun, SIGTERM and SIGINT belong to Open MPI: it passes SIGTERM to the ranks and kills them a
// second later, so they cannot wait for a checkpoint. mpirun forwards SIGUSR1 to every rank: send that
// to mpirun for a stop at the next checkpoint (the job scripts do).
#pragma once

#include <mpi.h>

namespace divcoll::mpi {

inline constexpr int kStoppedExit = 75;  // EX_TEMPFAIL: stopped at a checkpoint on request; --resume continues

// thrown on every rank by a checkpoint (Checkpointer) when a stop was asked for; carries the signal
struct StopRequested {
  int signal;
};

// installs the handlers (rank: only rank 0 prints; grace_s: the bound above)
void arm_stop_signals(int rank, double grace_s);
// restores the default actions and cancels the grace timer
void disarm_stop_signals();
// the signal that asked this rank to stop (0: none yet); the checkpoints (Checkpointer in mpi/checkpoint.hpp)
// agree on it across ranks, copy, and throw StopRequested on every rank
int stop_signal();
// "SIGTERM", "SIGINT", "SIGUSR1", ...
const char* signal_name(int sig);

}  // namespace divcoll::mpi
