// one verdict on every rank: a check that fails on one rank must stop every rank at the same point,
// never leave the others waiting in a collective call the failing rank skipped (issue 12).
#pragma once

#include <mpi.h>

#include <exception>
#include <string>

#include "common/check.hpp"

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
  MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPI_INT, MPI_MIN, comm);
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

// rank 0's string on every rank
inline std::string bcast_string(MPI_Comm comm, std::string s) {
  int len = static_cast<int>(s.size());
  MPI_Bcast(&len, 1, MPI_INT, 0, comm);
  s.resize(static_cast<size_t>(len));
  MPI_Bcast(s.data(), len, MPI_CHAR, 0, comm);
  return s;
}

}  // namespace divcoll::mpi
