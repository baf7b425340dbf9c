// the master/worker protocol: message tags, and the broadcast of a value from the master.
//
//   master → worker   kTask     [first | count | count sizes | count serialized tasks]   a block of items
//   worker → master   kResult   [first | count | count sizes | count serialized results] the block's results
//   master → worker   kRoundEnd (empty)                                                   no more items
//
// A round is collective: every rank enters farm() (mpi/scheduler.hpp) with the same item count. The master
// pushes each worker FarmOptions::depth blocks at once and answers every result with the next block, or,
// once the items are out, with kRoundEnd (once per worker; messages from the master arrive in the order it
// sent them, so no task of this round follows it; the next round's may, as the master can be ahead by rounds:
// a worker matches nothing after its kRoundEnd). The round ends when every item has a result on the master. Payloads
// are binary archives of plain data (stages/payload.hpp: pack, unpack).
#pragma once

#include <mpi.h>

#include <string>

#include "mpi/scheduler.hpp"
#include "mpi/wait.hpp"
#include "stages/payload.hpp"

namespace divcoll::mpi {

enum Tag : int { kTask = 2, kResult = 3, kRoundEnd = 4 };

using stages::pack;
using stages::unpack;

// rank 0's `value` on every rank (serialized, then broadcast); other ranks' `value` is ignored. The other
// ranks usually arrive first and wait while rank 0 works between rounds: they sleep (wait_sleeping), not
// spin in MPI_Bcast on a core that rank 0 or another job could use
template <class T>
T broadcast(MPI_Comm comm, const T& value) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::string bytes = rank == 0 ? pack(value) : std::string();
  int64_t n = static_cast<int64_t>(bytes.size());
  MPI_Request req;
  MPI_Ibcast(&n, 1, MPI_INT64_T, 0, comm, &req);
  wait_sleeping(req);
  bytes.resize(static_cast<size_t>(n));
  // every rank is here now: the payload goes in one blocking call. A non-blocking broadcast of a large
  // payload moves in segments, each needing both sides in MPI, and a sleeping wait made each segment wait up
  // to the backoff (a 1.3 MB broadcast took 25 ms this way)
  MPI_Bcast(bytes.data(), static_cast<int>(n), MPI_BYTE, 0, comm);
  return unpack<T>(bytes);
}

}  // namespace divcoll::mpi

