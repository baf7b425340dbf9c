// the stages of a run over the ranks (divcoll run, evolve), in run order: each stage the run runs that is not complete
// in the run file, through run_with_status (mpi/driver.hpp), and then its timings. A stage's timings are attributes of
// its group (every rank writes; `divcoll compare` leaves attributes out) and, on rank 0, lines of text: its wall time,
// how busy each rank was (seconds computing items) and the CPU seconds of its computing and serving threads, gathered
// on every rank, and rank 0's time outside the farm
#pragma once

#include <mpi.h>

#include "config/config.hpp"
#include "io/h5.hpp"
#include "mpi/checkpoint.hpp"

namespace divcoll::mpi {

// every stage of the run (`agents_only`, divcoll evolve: the agents stage) not complete in `file`, each with its
// timings; the stages commit through `checkpoints`, a stage's end forces a copy. A stop asked for by a signal leaves
// by StopRequested (mpi/stop.hpp) right after a checkpoint. Collective
void run_stages(MPI_Comm comm, const config::RunConfig& cfg, io::h5::File& file, Checkpointer& checkpoints, bool agents_only);

}  // namespace divcoll::mpi
