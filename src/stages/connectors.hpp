// the connectors stage (SPEC §6): every connector of every kind and replicate trained by backpropagation
// through its pairs, all in lock-step so that one round of work has K·R·B pair episodes to spread over
// the ranks. The master sums each connector's per-pair gradients in pair order (so the sum does not
// depend on who computed what), takes one optimizer step per connector, and broadcasts the weights.
//
// Run file (group /connectors; attributes status, iterations_done, kinds, replicates):
//   <kind>/params      (R × P_c)   trained weights, written when the stage completes
//   <kind>/curve_u     (I × R)     mean pair travel of each iteration's batch, u (before that step)
//   <kind>/curve_bl    (I × R)     the same in body lengths
//   <kind>/nan_pairs   (I × R)     pairs of the batch whose episode was not ok or whose gradient was not finite
//                                  (left out of the mean and the step)
//   state/params, state/adam_m, state/adam_v  (K·R × P_c)  the optimizer state at the last checkpoint
//   anchors            (P × 4)     each agent's back foot, front foot, back upper, front upper (§6.1), stored once
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "collective/builders.hpp"
#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "io/h5.hpp"
#include "stages/driver.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

inline constexpr uint64_t kConnectorsStage = config::stage_stream("connectors");

// one connector being trained: its springs, its batches (uniform: agent i with its clone;
// diverse: fresh random pairs each iteration from its stream), its training environment, and where its
// curves and weights go (row/column `column` of `group`'s datasets)
struct ConnectorSlot {
  collective::Tether tether;
  bool diverse = false;
  std::string env = "flat";
  uint64_t stream = 0;  // random stream of its initial weights (item 1000000) and batches (item = iteration)
  std::string group;
  int column = 0;
};
struct TrainSpec {
  std::string state_group;  // holds state/{params, adam_m, adam_v} and the attribute iterations_done
  std::string label;        // progress lines
  int iterations = 0, batch_pairs = 0, episode_steps = 0;
};

// the config values connector training reads: the run's seed, the [connectors] section and the run's physics
struct ConnectorsDef {
  uint64_t seed = 0;
  config::RunConfig::Connectors connectors;
  sim::RunPhysics physics;  // run.contact, run.precision
};
ConnectorsDef connectors_def(const config::RunConfig& cfg);

// connector training as a plan: every slot in lock-step, one round per iteration, one item per pair episode.
// The plain plan (Adam or a normalized step on the summed gradient) or, when any of the optimisation keys
// (evo/connector_opt.hpp) differs from its default, the extended one. It keeps references to `agents` and
// `slots`, which must outlive it
class ConnectorsPlan : public Plan {
 public:
  // master: the trained weights, one vector per slot, once finished
  virtual std::vector<std::vector<double>> weights() const = 0;
};
std::unique_ptr<ConnectorsPlan> make_connectors_plan(const ConnectorsDef& def,
                                                     const std::vector<morph::Agent>& agents,
                                                     const std::vector<ConnectorSlot>& slots, const TrainSpec& spec);

// trains every slot in lock-step (make_connectors_plan, driven), resuming from the state group's committed
// state; returns the trained weights on every rank
std::vector<std::vector<double>> train_connectors(Driver& driver, const std::vector<morph::Agent>& agents,
                                                  const std::vector<ConnectorSlot>& slots, const TrainSpec& spec);

// the slots' groups in first-appearance order, with their column counts
struct SlotGroups {
  std::vector<std::string> groups;
  std::vector<int> columns;
};
SlotGroups slot_groups(const std::vector<ConnectorSlot>& slots);

}  // namespace divcoll::stages
