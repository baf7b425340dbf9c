// a task farm over MPI with dynamic load balancing (protocol in mpi/protocol.hpp).
//
// Rank 0 is the master: it holds the items and pushes them to the workers in blocks of consecutive items,
// a few blocks ahead, so a worker always has its next block queued. On every rank items are computed in a
// thread of their own while the calling thread serves messages (non-blocking sends, MPI_Improbe and
// MPI_Imrecv), so nobody waits for a rank that is busy computing. The master computes items too when its
// node has a core per rank; with one rank it computes everything. Results are placed by item index, so
// they do not depend on who computed what, nor on the block sizes. A rank that waits sleeps (backing off
// up to 2 ms) instead of spinning in MPI, so an oversubscribed rank leaves its core to the ranks that compute;
// with a core per rank, a rank with nothing to compute looks again at once for up to 5 ms (a worker awaiting
// its next block, any rank in a wait between rounds), since that core has nothing else to do.
// DIVCOLL_FARM_TRACE=PREFIX writes every rank's farm events to PREFIX.RANK (divcoll_post.farm_trace).
#pragma once

#include <mpi.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace divcoll::mpi {

struct FarmOptions {
  // the master computes items too (in a thread beside its messages) when the ranks on its node are no more
  // than the node's cores; otherwise, or when false, it only coordinates
  bool master_works = true;
  // called on the master after each finished item with (items done, items total)
  std::function<void(int, int)> progress;
  // items per task message: 0 = automatic (guided: ⌈items left / (4 × computing ranks)⌉, at most max_block;
  // with costs, the fewest dearest items that make that share of the cost left);
  // a block's results come back in one message. Results never depend on it.
  int block = 0;
  int max_block = 64;
  // blocks a worker holds at once (one computing, the others queued). In a round's tail (no more items left
  // than 4 per computing rank, automatic blocks) a worker holds one item at a time and gets the next when its
  // result comes back, so that no item waits in one worker's queue while another rank has nothing to do
  int depth = 2;
  // estimates of each item's compute time, any unit, all > 0 (significant on rank 0 only; empty: all equal).
  // The master hands items out dearest first (equal costs in index order) and sizes its guided blocks by
  // cost, so a round ends on cheap items and its tail (where ranks wait for the last item) is short. Results
  // are still placed, and folded by on_result, by item index: they never depend on it. One rank computes in
  // index order.
  std::vector<double> costs;
  // called on the master, in item order, as soon as items 0..i all have results (from farm()'s calling
  // thread, while later items are still being computed): lets the caller fold results during the round
  std::function<void(int64_t, const std::string&)> on_result;
};

// items: serialized tasks (significant on rank 0 only). compute: task bytes → result bytes; it runs in a
// thread of farm()'s own (one at a time on each rank), so it must not call MPI.
// Returns on every rank a vector of n results (bytes); a rank holds the results it computed, and
// rank 0 holds all of them. owner[i] (same on every rank) is the rank that computed item i.
struct FarmResult {
  std::vector<std::string> results;
  std::vector<int> owner;
};
// this rank's running totals over every farm() call: seconds inside compute() and inside farm()
// (the rest of a stage's wall time is the master's own work, I/O and checkpoints), CPU seconds of the
// serving thread (the calling thread, inside farm(), beside the computing thread; 0 at one rank, where the
// calling thread computes), and on rank 0 the cost of serving: seconds spent sending tasks and taking in
// results, messages and bytes each way; last, the CPU seconds of the computing thread inside compute() (its
// wall seconds there are compute_s)
struct FarmClock {
  double compute_s = 0, farm_s = 0;
  long items = 0;
  double serve_cpu_s = 0, task_s = 0, result_s = 0;
  long task_msgs = 0, result_msgs = 0, results = 0;
  double task_bytes = 0, result_bytes = 0;
  double compute_cpu_s = 0;
};
FarmClock& farm_clock();

FarmResult farm(MPI_Comm comm, const std::vector<std::string>& items,
                const std::function<std::string(const std::string&)>& compute, const FarmOptions& opt = {});

}  // namespace divcoll::mpi
