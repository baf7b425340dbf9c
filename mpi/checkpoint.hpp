// crash-safe run files. HDF5 has no journal: a job killed while it writes can leave the file's metadata
// half-updated, older generations included. So the run file is created under a temporary name and
// renamed into place, and at every checkpoint it is flushed and copied to RUN.h5.ckpt (copy, fsync,
// atomic rename). --resume validates RUN.h5 by reading every dataset and falls back to the checkpoint.
#pragma once

#include <mpi.h>

#include <string>

#include "io/h5.hpp"

namespace divcoll::mpi {

std::string checkpoint_path(const std::string& run_path);

// every rank calls it: flush, then rank 0 copies the file to its checkpoint
void checkpoint(MPI_Comm comm, io::h5::File& file, const std::string& run_path);

// rank-local: a divcoll run file whose every dataset reads back; `why` says what is wrong otherwise
bool valid_run_file(const std::string& path, std::string* why);

// rank 0 decides what to resume from: the checkpoint when there is one that reads back (it replaces the run
// file), else the run file as it is (a finished run's, whose checkpoint is removed); returns
// (on every rank) true if there is a run to continue, false if the run must start from nothing.
// Throws InputError if `run_path` exists, is damaged and has no checkpoint.
bool prepare_resume(MPI_Comm comm, const std::string& run_path);

// removes the checkpoint (rank 0) once the run is complete
void remove_checkpoint(MPI_Comm comm, const std::string& run_path);

}  // namespace divcoll::mpi
