// a stage as a plan: what it computes, round by round, and nothing about how (ranks, files, printing).
//
// A plan has rounds (a stage's generations or iterations), each a list of items (serialized tasks). A farm
// runs it: the driver (mpi/driver.hpp) spreads a round's items over the ranks, hands the plan every result in
// item order (so a round's reduction does not depend on the rank count), then asks it what the round records.
// Between rounds it commits the plan's state and the round counter together, as one checkpoint step, and
// resumes from the last commit. The serial farm (stages/serial.hpp) runs the same methods in one process,
// without files. Both follow the plan's schedule (stages/schedule.hpp): which calls are made in which order is
// decided there, once. The plan's methods run on the master unless noted; compute() runs on every rank.
//
// To add a stage: write its plan (this interface) and its rows in the run-file schema (src/io/run_file.cpp).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace divcoll::stages {

// rows of one run-file dataset: `rows` of a dataset of dims `dims` (created on first use), row-major values
struct Record {
  std::string path;
  std::vector<uint64_t> dims;
  std::vector<int64_t> rows;
  std::variant<std::vector<double>, std::vector<int64_t>, std::vector<int32_t>, std::vector<uint8_t>, std::vector<float>> values;
};
using Records = std::vector<Record>;

// an attribute of the plan's group (a name with '/' in it: of that subgroup, e.g. "adversity/deploy_mismatches"):
// text or an integer
struct Attribute {
  std::string name;
  std::variant<std::string, int64_t> value;
};

// the committed state read back at resume: dataset path -> its values (row-major)
using StoredState = std::map<std::string, std::vector<double>>;

class Plan {
 public:
  virtual ~Plan() = default;

  // ---- what it is ----
  struct Info {
    std::string label;                        // progress lines ("connectors", "graded same_shape", ...)
    std::string group;                        // the run-file group holding its round counter
    std::string counter = "iterations_done";  // that counter's attribute
    std::string round_word = "iteration";     // progress lines
    std::string item_word = "items";          // progress lines (per second)
    int commit_every = 0;                     // rounds per commit; 0: output.checkpoint_every
    // farm passes per round: a round of several passes (e.g. agents alone, then pairs that use their
    // results) is counted and committed as one. The methods marked (step) get step = round · passes + pass
    int passes = 1;
    // rounds that need nothing from each other (no round input; compute() reads only its item): the driver
    // farms several in one call when a round alone has few items per rank (kTogetherItemsPerRank,
    // stages/schedule.hpp; its tail, where ranks wait for the last item, would be a large share), and commits
    // after the last of them. Each is still reduced, recorded and counted as its own round, but items() of the
    // later rounds comes before the earlier rounds' reduce() and end_round(), so the plan keeps a round's
    // results by its step. Passes must be 1
    bool independent_rounds = false;
  };
  virtual Info info() const = 0;
  virtual int rounds() const = 0;                       // counted rounds: 0 .. rounds()-1
  virtual bool closing_round() const { return false; }  // one more, uncounted round (index rounds()), redone on resume
  // written when the plan starts (every rank: the same values), and rows drawn once (master)
  virtual std::vector<Attribute> attributes() const { return {}; }
  virtual Records setup() { return {}; }

  // ---- state ----
  // the datasets of its state (start() gets them back after a resume); rows written by end_round() count
  // as committed with the round
  virtual std::vector<std::string> state_paths() const { return {}; }
  // integer attributes of its state (names as Attribute's; every rank: the names, the master: the values),
  // committed with the counter; start() gets their committed values back under their names, one value each
  virtual std::vector<std::pair<std::string, int64_t>> state_attributes() const { return {}; }
  // master: from nothing (done == 0) or from the state committed with `done` rounds
  virtual void start(int done, const StoredState& stored) = 0;
  // master: its state now, to commit with the counter
  virtual Records state() const { return {}; }

  // ---- a round (a pass of one, with Info::passes > 1) ----
  // master: data every rank needs for compute() in this step (e.g. the weights); handed to take_input()
  virtual std::string round_input(int step) { (void)step; return {}; }
  // every rank
  virtual void take_input(int step, const std::string& input) { (void)step, (void)input; }
  // master: the step's items
  virtual std::vector<std::string> items(int step) = 0;
  // master, right after items(step): optional estimates of each item's compute time (any unit: agents per
  // episode, seconds an agent's parent took to train), one per item, or empty. The farm hands the dearest out
  // first so that the round ends on cheap items; only who computes what changes, never a result
  virtual std::vector<double> item_costs(int step) const { (void)step; return {}; }
  // every rank, in a thread of the farm: one item's pure compute (task bytes -> result bytes)
  virtual std::string compute(const std::string& item) = 0;
  // master: every result of the step, in item order
  virtual void reduce(int step, int64_t item, const std::string& result) = 0;
  // master: after the step's last result: its reduction, and the rows it records
  virtual Records end_round(int step) = 0;
  // master: right after end_round(): what it met that deserves a warning (numerical trouble, each with where it
  // happened), one line each, taken. The driver says them on standard error; a plan prints nothing
  virtual std::vector<std::string> take_warnings() { return {}; }
  // master: one line's summary of the round just ended (after "label: iteration k/N: ")
  virtual std::string summary(int round) const { (void)round; return {}; }
  // master: the rows recorded once the rounds are done (written again when a finished stage is resumed),
  // and a line's summary of them (printed after "label: " when not empty)
  virtual Records finish() { return {}; }
  virtual std::string finish_summary() const { return {}; }
};

}  // namespace divcoll::stages
