// what a stage's runner asks of the layer that runs its plans: the config, the run file, a plan driven to its
// end, and the few collective steps a runner takes between plans. The MPI driver (mpi/driver.hpp, MpiDriver)
// implements it over the ranks; every rank calls the runner with its own Driver, and every rank makes the same
// calls on the run file (reads included: a read made by one rank alone unbalances the ranks' HDF5 metadata
// caches, io/h5.hpp).
//
// A runner (run_<name>_stage, declared from the stage list DIVCOLL_STAGES in src/config/pipeline.hpp) reads its
// stage's inputs from the run file, builds its plans and drive()s them; it never farms, writes a status or
// checkpoints itself.
#pragma once

#include <functional>
#include <string>

#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "io/h5.hpp"
#include "stages/payload.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

class Driver {
 public:
  virtual ~Driver() = default;
  virtual const config::RunConfig& config() const = 0;
  virtual io::h5::File& file() const = 0;
  // whether this process holds the master's plan (the one whose start(), reduce() and records count)
  virtual bool master() const = 0;
  // runs (or resumes) `plan` until its rounds are done
  virtual void drive(Plan& plan) = 0;
  // the master's bytes on every process (the others' are ignored)
  virtual std::string broadcast(const std::string& bytes) = 0;
  // writes the master's records (every process calls it; the others' are ignored)
  virtual void write(const Records& records) = 0;
  // runs `body` as a part with its own status in `group` (a graded population, its agents): nothing if the
  // status is "complete" (returns false); else "running", body(), "complete" and a checkpoint
  virtual bool with_status(const std::string& group, const std::function<void()>& body) = 0;
};

// the master's `value` on every process
template <class T>
T broadcast(Driver& driver, const T& value) {
  return unpack<T>(driver.broadcast(driver.master() ? pack(value) : std::string()));
}

// whether `group`'s status is "complete" (every process reads)
bool complete(const io::h5::Node& file, const std::string& group);

// ---- the stages ----------------------------------------------------------------------------------------
// every stage's runner, declared from the one stage list (config/pipeline.hpp DIVCOLL_STAGES) and defined beside
// the stage's plans (stages/<name>.cpp); mpi/driver.hpp lists them with their MPI driver (mpi::kStages)
#define DIVCOLL_STAGE_RUNNER(name, stream, reads) void run_##name##_stage(Driver& driver);
DIVCOLL_STAGES(DIVCOLL_STAGE_RUNNER)
#undef DIVCOLL_STAGE_RUNNER

}  // namespace divcoll::stages
