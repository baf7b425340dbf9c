// waiting in MPI without spinning: Open MPI's blocking calls poll the core until they complete, so a rank
// that waits for another (rank 0 between rounds, a checkpoint copy, a stage's serial end) would take a core
// the working rank or another job could use. These wait on the non-blocking form and sleep between tests
// (20 µs doubling to 500 µs; mpi/scheduler.cpp), after testing without sleeping for up to 5 ms when every rank
// of the node has a core of its own (known from the first farm(); the core is then idle anyway)
#pragma once

#include <mpi.h>

namespace divcoll::mpi {

// waits for a non-blocking MPI request, sleeping between tests
void wait_sleeping(MPI_Request& req);
// MPI_Barrier, waited on sleeping. Collective
void barrier_sleeping(MPI_Comm comm);
// MPI_Allreduce of one int in place, waited on sleeping. Collective
void allreduce_int_sleeping(MPI_Comm comm, int& value, MPI_Op op);

}  // namespace divcoll::mpi
