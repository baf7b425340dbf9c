// the serial farm: runs a plan (stages/plan.hpp) in one process, without files, and returns what it records. It
// walks the plan's schedule (stages/schedule.hpp), the same sequence of farm calls the driver (mpi/driver.hpp)
// makes over ranks: each call's items computed (in the order SerialOptions::order says), reduced in item order and
// their steps ended. The tests run every stage's plans through it (tests/stages/).
//
// Independent rounds are farmed one round a call unless SerialOptions asks for more (rounds_per_farm), or for the
// driver's own farms at some rank count (ranks). Each round's warnings (Plan::take_warnings) are collected, not printed. The state is taken where the driver commits its last one: after
// the last counted round run, before the closing round.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "stages/plan.hpp"
#include "stages/schedule.hpp"

namespace divcoll::stages {

struct SerialOptions {
  int from = 0;        // rounds already done: the plan starts from the state committed with them
  StoredState stored;  // that state (committed_state() of the run that did them)
  int until = -1;      // stop once this many rounds are done (-1: every round, then the closing round and finish())
  // the order items are computed in; results are reduced in item order whatever it is
  enum class Order { items, dearest_first, reversed, shuffled } order = Order::items;
  uint64_t shuffle_seed = 0;  // Order::shuffled
  int rounds_per_farm = 1;    // a plan with independent rounds: rounds farmed together (at most)
  int ranks = 0;              // > 0: farms as the driver's on this many ranks (driver_schedule; rounds_per_farm unused)
  int checkpoint_every = 1;   // rounds per commit (output.checkpoint_every; Plan::Info::commit_every wins)
  std::function<void(const FarmCall&)> on_farm;  // sees every farm call before its items are computed
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
