// `divcoll bench-farm`: the task farm's master measured alone (it prints; it is not a test).
//
// Under `mpirun -np P`, rounds of synthetic items of a fixed cost: an item sleeps for --item-ms (so the
// workers use no core and, even oversubscribed, the machine is the master's) and returns a result of
// --result-bytes (a serialized vector of doubles, like a connector's gradient). Rank 0 prints, per round
// and in total, the master's CPU µs per item, the µs it spends sending a task block and taking in a result
// block, the bytes per result, the messages per round, the workers' busy share and the round's
// efficiency against ⌈items / workers⌉ item times. With --fold the master also unpacks every result and
// adds it into one sum in item order, as the connectors stage does with gradients: after the round (as
// the stages do) or during it (FarmOptions::on_result).
#pragma once

#include <string>

namespace divcoll::cli {

struct BenchFarmArgs {
  double item_ms = 5.0;         // cost of one item (a sleep)
  int result_bytes = 11800;     // bytes of one result (a connector's gradient: 1473 doubles ≈ 11.8 kB)
  int task_bytes = 16;          // bytes of one task
  int items = 4000;             // items per round (paper-scale connectors: 4000; specialists: 12000)
  int rounds = 3;               // rounds measured (after one warm-up round)
  int block = 0;                // FarmOptions::block (0: guided)
  int max_block = 64;           // FarmOptions::max_block
  int depth = 2;                // FarmOptions::depth
  std::string fold = "after";   // none, after (the round) or during (on_result)
  bool master_works = false;    // the master computes items too
};

// initialises MPI, runs, finalises; returns the exit code
int bench_farm_main(int argc, char** argv, const BenchFarmArgs& args);

}  // namespace divcoll::cli
