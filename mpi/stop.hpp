// clean stops (issue 12). SIGTERM, SIGINT and SIGUSR1 ask the run to stop right after its next checkpoint:
// every rank learns of it at that checkpoint (an allreduce), the run file is closed, the lock dropped, and
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

// thrown on every rank by stop_point() when a stop was asked for; carries the signal
struct StopRequested {
  int signal;
};

// installs the handlers (rank: only rank 0 prints; grace_s: the bound above)
void arm_stop_signals(int rank, double grace_s);
// restores the default actions and cancels the grace timer
void disarm_stop_signals();
// collective, right after a checkpoint: throws StopRequested on every rank if any rank got a signal
void stop_point(MPI_Comm comm);
// "SIGTERM", "SIGINT", "SIGUSR1", ...
const char* signal_name(int sig);

}  // namespace divcoll::mpi
