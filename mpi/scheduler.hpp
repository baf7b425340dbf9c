// a task farm over MPI with dynamic load balancing (protocol in mpi/protocol.hpp).
//
// Rank 0 is the master: it holds the items and hands them out as workers ask. When ranks ≤ cores it
// also computes items itself between messages, so `mpirun -np 2` on 2 cores uses both; with one rank it
// computes everything. Results are placed by item index, so they do not depend on who computed what.
#pragma once

#include <mpi.h>

#include <functional>
#include <string>
#include <vector>

namespace divcoll::mpi {

struct FarmOptions {
  bool master_works = true;  // the master computes items between messages
  // called on the master after each finished item with (items done, items total)
  std::function<void(int, int)> progress;
};

// items: serialized tasks (significant on rank 0 only). compute: task bytes → result bytes.
// Returns on every rank a vector of n results (bytes); a rank holds the results it computed, and
// rank 0 holds all of them. owner[i] (same on every rank) is the rank that computed item i.
struct FarmResult {
  std::vector<std::string> results;
  std::vector<int> owner;
};
// this rank's running totals over every farm() call: seconds inside compute() and inside farm()
// (the rest of a stage's wall time is the master's own work, I/O and checkpoints)
struct FarmClock {
  double compute_s = 0, farm_s = 0;
  long items = 0;
};
FarmClock& farm_clock();

FarmResult farm(MPI_Comm comm, const std::vector<std::string>& items,
                const std::function<std::string(const std::string&)>& compute, const FarmOptions& opt = {});

}  // namespace divcoll::mpi
