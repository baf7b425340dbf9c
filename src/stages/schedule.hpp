// a plan's schedule: the one sequence of farm calls a plan (stages/plan.hpp) turns into, made in one place for
// both farms that run plans: the MPI driver (mpi/driver.hpp) and the serial farm (stages/serial.hpp).
//
// A farm call is one pass of a round, or, for a plan with independent rounds, several rounds farmed together.
// For each call the master's schedule asks the plan, step by step, for the round input (and hands it to the plan's
// take_input), the items and their costs; other processes follow the master's call (FarmHead), handing the same
// inputs to their own plans. The farm computes the call's items; the schedule then hands each result to the
// step it belongs to (reduce, in item order) and ends the call's steps (end_round). The call says whether a commit
// follows it (every commit_every rounds, and after the last round run) and whether it is the closing round.
// Nothing here farms, writes or talks to other processes.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "stages/plan.hpp"

namespace divcoll::stages {

// a plan's independent rounds (Plan::Info::independent_rounds) are farmed together by the driver until a farm
// has this many items per rank: a farm's tail costs each rank about half an item, under 2% of a farm of 32 items
// per rank (at 8, the quick preset's scaling rounds lost 4% of a worker's time in their tails)
inline constexpr size_t kTogetherItemsPerRank = 32;

struct ScheduleOptions {
  int from = 0;    // rounds already done: the schedule starts with round `from`
  int until = -1;  // stop once this many rounds are done (a commit; no closing round); -1: every round, then the
                   // closing round if the plan has one
  int commit_every = 1;  // rounds per commit; Plan::Info::commit_every wins when it is set
  // independent rounds farmed together: more rounds join a farm while it holds fewer than `together_items`
  // items (0: no bound) and fewer than `together_rounds` rounds (0: no bound), and not after a round whose end
  // `ends_farm` names (rounds done then; a commit that must stay the commit of one farm)
  size_t together_items = 0;
  int together_rounds = 1;
  std::function<bool(int)> ends_farm;
};

// the schedule the MPI driver runs on `ranks` ranks from `done` rounds done: every round and the closing round,
// independent rounds together until a farm holds kTogetherItemsPerRank items per rank, a commit every
// `checkpoint_every` rounds (output.checkpoint_every) and after the last
ScheduleOptions driver_schedule(int done, int ranks, int checkpoint_every);

// what every process needs of a farm call (the master's is handed to the others)
struct FarmHead {
  std::vector<int> steps;           // the steps it serves, in order (Plan's `step`: round · passes + pass)
  std::vector<std::string> inputs;  // each step's round input, for take_input
  int round = 0;                    // the (first) round it serves; rounds() for the closing round
  int rounds = 1;                   // the rounds it serves: several when independent rounds are farmed together
  bool ends_rounds = true;          // its rounds' last pass: after it they are done (the closing round: recorded)
  bool commit = false;              // a commit follows it, of round + rounds rounds done
  bool closing = false;             // the closing round (uncounted)
  bool operator==(const FarmHead&) const = default;
};
template <class Ar>
void serialize(Ar& ar, FarmHead& h, unsigned) {
  ar & h.steps & h.inputs & h.round & h.rounds & h.ends_rounds & h.commit & h.closing;
}

// a farm call on the master: its head, and the items of its steps one after another
struct FarmCall : FarmHead {
  std::vector<std::string> items;
  std::vector<int64_t> first;  // where each step's items start in `items`, and items.size() last
  std::vector<double> costs;   // the plan's estimate of each item's cost, or empty (not every step gave them)
  bool operator==(const FarmCall&) const = default;
};

class Schedule {
 public:
  // every process, with its own plan (on the master: started); refuses a plan with independent rounds and passes
  Schedule(Plan& plan, ScheduleOptions options);

  bool done() const { return round_ >= end_; }  // no farm call left
  // the next call is the closing round's first: the driver writes its last commit before the plan moves on
  bool closing_next() const { return !done() && round_ >= rounds_ && pass_ == 0; }
  int rounds_done() const { return std::min(round_, rounds_); }
  int stop() const { return stop_; }  // the rounds done when it stops, its last commit
  int pass() const { return pass_; }  // the next call's pass of its round

  // master: the next call, its inputs taken by the plan, its items and their costs made
  FarmCall next();
  // another process: follows the master's call `head` (its plan takes the inputs)
  void follow(const FarmHead& head);
  // master: the result of item `item` of `call`, handed to its step (in item order)
  void reduce(const FarmCall& call, int64_t item, const std::string& result);
  // master: after the call's last result: end_round of each of its steps, their records in order
  Records end(const FarmCall& call);

  // the master's time in next(): asking for the inputs (round_input, take_input), and the items (items, costs)
  double input_s() const { return input_s_; }
  double items_s() const { return items_s_; }

 private:
  void add_step(FarmCall& call, int step, bool& costed);
  void advance(const FarmHead& head);

  Plan& plan_;
  Plan::Info info_;
  ScheduleOptions o_;
  int rounds_ = 0, stop_ = 0, end_ = 0, every_ = 1;
  int round_ = 0, pass_ = 0;  // the next call's
  double input_s_ = 0, items_s_ = 0;
};

}  // namespace divcoll::stages
