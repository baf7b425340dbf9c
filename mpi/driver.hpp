// the one driver: runs any stage's plan (stages/plan.hpp) over the ranks.
//
// What the plan's rounds turn into, farm call by farm call (the steps, their items and costs, where a commit
// falls), is the plan's schedule (stages/schedule.hpp), the same the serial farm walks. The driver does the MPI
// work around it: the master makes each call and broadcasts what the other ranks need of it (its steps and their
// inputs), the task farm (mpi/scheduler.hpp) computes its items, results go to the plan in item order; and it owns
// what every stage shares: the round counter and resume, writing the plan's rows (every rank takes part in each
// write: parallel HDF5), the commit of a round's state with its counter, progress lines with an ETA, and the
// stage's timing.
//
// Commit: the plan's state and the counter are written together and then checkpointed (mpi/checkpoint.hpp),
// one step; --resume starts from the last checkpoint, never from what a killed job left in the run file
// after it, so a kill between the state and the counter (or anywhere else) resumes a consistent pair.
// Since only a checkpoint is resumed from, the rounds' rows and the state wait on the master until a commit
// that copies the run file (output.checkpoint_interval_s), and the end of the plan: then they are written,
// a dataset's rows from many rounds in one write, so the workers do not wait for a write every round.
// The hidden debug hook DIVCOLL_DEBUG_EXIT_IN_COMMIT=<group>:<rounds done> (or <group>@<counter>:<rounds done>,
// where plans share a group) makes every rank flush the run
// file and exit (code 86) right between writing that commit's state and its counter (tests/mpi/commit_kill_test.sh).
#pragma once

#include <mpi.h>

#include <array>
#include <cstddef>
#include <functional>
#include <map>
#include <string>

#include "config/config.hpp"
#include "io/h5.hpp"
#include "config/pipeline.hpp"
#include "stages/driver.hpp"
#include "stages/plan.hpp"

namespace divcoll::mpi {

using stages::Attribute;
using stages::complete;
using stages::Plan;
using stages::Record;
using stages::Records;
using stages::StoredState;

// runs (or resumes) `plan` on `comm` until its rounds are done; every rank calls it with its own plan
// object (built from the same inputs). `checkpoint` is called (collectively) at each commit: after every
// output.checkpoint_every rounds and after the last one.
void drive(MPI_Comm comm, const config::RunConfig& cfg, io::h5::File& file, Plan& plan,
           const std::function<void()>& checkpoint);

// this rank's running totals over every drive() call, in wall seconds, of its time outside farm() (the time
// inside is FarmClock::farm_s). Outside the farm every worker waits for the master, so on rank 0
// input + items + writes + commits is the serial time that bounds the speed-up with ranks
struct DriverClock {
  double input_s = 0;    // broadcasting the round's input (plan.round_input, take_input)
  double items_s = 0;    // the master building the round's items (plan.items)
  double writes_s = 0;   // the round's records (plan.end_round and the parallel writes)
  double commits_s = 0;  // commits: the state, the counter and the checkpoint
  long rounds = 0;
};
DriverClock& driver_clock();

// a stage, or a part of one with its own status (a graded population, its agents), run with its status in
// `group` (created if missing): nothing if the status is "complete" (returns false); else status "running",
// body(), status "complete" and `checkpoint` (divcoll run passes a forced copy for a stage's end). The only
// writer of status; every rank calls it
bool run_with_status(io::h5::File& file, const std::string& group, const std::function<void()>& checkpoint,
                     const std::function<void()>& body);

// records waiting to be written (the driver's rounds between copies): one record per dataset, its rows in the
// order they came, a row that comes again replacing its values
class RecordQueue {
 public:
  void add(Records records);
  Records take();                            // everything waiting, in the order the datasets came; empties
  size_t bytes() const { return bytes_; }   // the values added since the last take()

 private:
  Records waiting_;
  std::map<std::string, size_t> index_;
  size_t bytes_ = 0;
};

// writes the master's records; every rank calls it (the others' `records` are ignored)
void write_records(MPI_Comm comm, const io::h5::Node& file, const Records& records);

// ---- the stages ----------------------------------------------------------------------------------------
// the runners' driver (stages/driver.hpp) over the ranks of `comm`: drive(), broadcast(), write_records() and
// run_with_status() above
class MpiDriver final : public stages::Driver {
 public:
  MpiDriver(MPI_Comm comm, const config::RunConfig& cfg, io::h5::File& file, const std::function<void()>& checkpoint);
  const config::RunConfig& config() const override { return cfg_; }
  io::h5::File& file() const override { return file_; }
  bool master() const override { return rank_ == 0; }
  void drive(Plan& plan) override;
  std::string broadcast(const std::string& bytes) override;
  void write(const Records& records) override;
  bool with_status(const std::string& group, const std::function<void()>& body) override;

 private:
  MPI_Comm comm_;
  const config::RunConfig& cfg_;
  io::h5::File& file_;
  const std::function<void()>& checkpoint_;
  int rank_ = 0;
};

// a stage's runner (stages/driver.hpp: run_<name>_stage) on `comm`, with an MpiDriver (every rank calls it)
using StageRunner = void (*)(MPI_Comm, const config::RunConfig&, io::h5::File&, const std::function<void()>&);
template <void (*run)(stages::Driver&)>
void run_stage(MPI_Comm comm, const config::RunConfig& cfg, io::h5::File& file, const std::function<void()>& checkpoint) {
  MpiDriver driver(comm, cfg, file, checkpoint);
  run(driver);
}

struct Stage {
  config::StageInfo info;
  StageRunner run;
};
// the stages in the order they run
#define DIVCOLL_STAGE(name, stream, reads) Stage{{#name, stream, reads}, run_stage<stages::run_##name##_stage>},
inline const std::array kStages = {DIVCOLL_STAGES(DIVCOLL_STAGE)};
#undef DIVCOLL_STAGE

}  // namespace divcoll::mpi
