// one verdict on every rank: a check that fails on one rank must stop every rank at the same point,
// never leave the others waiting in a collective call the failing rank skipped.
#pragma once

#include <mpi.h>

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "common/check.hpp"
#include "io/h5.hpp"
#include "mpi/wait.hpp"

namespace divcoll::mpi {

// every rank runs `f`; if it throws on any rank, every rank throws InputError with the message of the
// lowest failing rank. Collective: every rank of `comm` must call it.
template <class F>
void agree_all(MPI_Comm comm, F&& f) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::string err;
  bool bad = false;
  try {
    f();
  } catch (const std::exception& e) {
    err = e.what();
    bad = true;
  }
  int first = bad ? rank : size;
  allreduce_int_sleeping(comm, first, MPI_MIN);  // the others often wait here for rank 0's check
  if (first == size) return;
  int len = static_cast<int>(err.size());
  MPI_Bcast(&len, 1, MPI_INT, first, comm);
  err.resize(static_cast<size_t>(len));
  MPI_Bcast(err.data(), len, MPI_CHAR, first, comm);
  throw InputError(err);
}

// rank 0 runs `f`; its failure is every rank's
template <class F>
void agree_rank0(MPI_Comm comm, F&& f) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  agree_all(comm, [&] {
    if (rank == 0) f();
  });
}

// with DIVCOLL_DEBUG_SYMMETRIC_IO=1 (io/h5.hpp): every rank has made the same HDF5 calls on the run file so
// far, else each rank prints its calls since the last check and every rank throws, naming `at`. Collective.
inline void check_symmetric_io(MPI_Comm comm, const char* at) {
  if (!io::h5::journal_enabled()) return;
  io::h5::Journal& j = io::h5::journal();
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const uint64_t mine[2] = {j.calls, j.digest};
  std::vector<uint64_t> all(2 * static_cast<size_t>(size));
  MPI_Allgather(mine, 2, MPI_UINT64_T, all.data(), 2, MPI_UINT64_T, comm);
  int bad = 0;
  for (int r = 1; r < size && bad == 0; ++r)
    if (all[2 * r] != all[0] || all[2 * r + 1] != all[1]) bad = r;
  if (bad == 0) {
    j.since_check.clear();
    return;
  }
  for (int r : {0, bad}) {
    if (rank == r) {
      std::fprintf(stderr, "divcoll: rank %d's HDF5 calls since the last check (%zu):\n", rank, j.since_check.size());
      for (const std::string& s : j.since_check) std::fprintf(stderr, "  rank %d: %s\n", rank, s.c_str());
      std::fflush(stderr);
    }
    barrier_sleeping(comm);
  }
  throw InputError(msg() << "ranks made different HDF5 calls on the run file before " << at << ": rank 0 "
                         << all[0] << " calls, rank " << bad << " " << all[2 * bad]
                         << " (their calls since the last check are printed above); every rank must make the same "
                            "calls, reads included");
}

}  // namespace divcoll::mpi
