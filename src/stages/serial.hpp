// the serial farm: runs a plan (stages/plan.hpp) in one process, calling its methods in the order the driver
// (mpi/driver.hpp) calls them over ranks, without files, and returns what it records. The tests run every stage's
// plans through it (tests/stages/).
//
// Per round (per pass of one, with Plan::Info::passes > 1): round_input, take_input, items and item_costs, every
// item's compute (in the order SerialOptions::order says), reduce in item order, end_round and take_warnings,
// summary. Rounds of a plan with independent rounds may be farmed together as the driver does
// (SerialOptions::rounds_per_farm): the items of every round of the farm first, then each round reduced and ended. The state is taken where the driver
// commits its last one: after the last counted round run, before the closing round.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "stages/plan.hpp"

namespace divcoll::stages {

struct SerialOptions {
  int from = 0;        // rounds already done: the plan starts from the state committed with them
  StoredState stored;  // that state (committed_state() of the run that did them)
  int until = -1;      // stop once this many rounds are done (-1: every round, then the closing round and finish())
  // the order items are computed in; results are reduced in item order whatever it is
  enum class Order { items, dearest_first, reversed, shuffled } order = Order::items;
  uint64_t shuffle_seed = 0;  // Order::shuffled
  int rounds_per_farm = 1;    // a plan with independent rounds: rounds farmed together (at most)
};

struct SerialRun {
  std::vector<Attribute> attributes;  // attributes()
  Records setup;                      // setup()
  Records rounds;                     // end_round() of every step run, in order
  Records state;                      // state() after the last counted round run (a commit's state)
  std::vector<std::pair<std::string, int64_t>> state_attributes;  // and its state attributes
  Records finish;                     // finish(), when the last round was run
  std::vector<std::string> summaries;  // summary() of every counted round run
  std::vector<std::string> warnings;   // take_warnings() after every end_round(), in order
  std::string finish_summary;
  int done = 0;        // rounds done at the end
  int64_t items = 0;   // items computed
  Records written() const;  // setup, rounds, state and finish: everything the driver writes, in order
};

// runs `plan` as the master's plan. `worker`, if given, is a second plan built from the same inputs as a worker
// rank builds it (without what only the master holds): it gets every step's input and computes every item, so
// a plan whose compute() reads the master's state fails
SerialRun run_serial(Plan& plan, const SerialOptions& options = {}, Plan* worker = nullptr);

// a dataset as the records leave it: its dims, its values row-major as doubles (rows never written: NaN), and the
// index of its type in Record::values
struct Dataset {
  std::vector<uint64_t> dims;
  std::vector<double> values;
  size_t type = 0;
};
// the datasets the records write, in order (a row written again takes the later values)
std::map<std::string, Dataset> datasets(const Records& records);
std::map<std::string, Dataset> datasets(const std::vector<Records>& sessions);

// what a resume reads back after `sessions` of the plan (each one's SerialRun::written()): the values of its
// state_paths() and the last value of each of its state attributes, as the driver hands them to start()
StoredState committed_state(const Plan& plan, const std::vector<const SerialRun*>& sessions);

}  // namespace divcoll::stages
