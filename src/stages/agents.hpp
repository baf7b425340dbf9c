// the agents stage (SPEC §4): a population co-designed by evolution (on the master) and gradient
// descent (on every rank), written generation by generation into the run file.
//
// Run file layout of the stage (group /agents):
//   attributes  status ("running" | "complete"), generations_done (groups gen_000 .. complete), population
//   gen_NNN/    every candidate of generation NNN (gen_000: the P random agents after training; later
//               generations: the P parents, then their P offspring), one row each:
//     id, parent (int64; parent −1 in generation 0), cells, springs (int64 genotypes),
//     rest_pos (M×11×2, u), spring_i, spring_j (M×21 int32), rest_length (M×21, u), amplitude (M×21),
//     params (M×P_a), fitness (M, travel in body lengths), travel_u (M, u), status (M uint8: 0 ok,
//     1 nan, 2 unstable), descriptor (M×9), uniqueness (M, in the whole pool), survived (M uint8),
//     curve_u (M×(epochs+1): travel at each evaluation of this generation's training; NaN for parents)
//   final/      the surviving population after the last generation (same datasets, P rows), which the
//               later stages read
// A generation is a round of the plan: --resume continues after the last committed one, bit-identically.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "evo/evolution.hpp"
#include "stages/driver.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

// random-number stage id of generation g of the agents stage (SPEC §10: seeds are (run, stage, item))
inline constexpr uint64_t kAgentsStage = config::stage_stream("agents");

// where and how a population is evolved: the main one (defaults) or a graded-diversity one (SPEC §7.5)
struct AgentsSpec {
  std::string group = "agents";        // run-file group of the generations and the final population
  std::string label = "agents";        // progress lines
  uint64_t stream = kAgentsStage;      // random stream of generation g: stream + g
  uint32_t fixed_cells = 0;            // generation 0 takes this body (0: random bodies)
  uint32_t fixed_springs = 0;          // ... and these springs (0: random springs)
  bool spring_descriptor = false;      // uniqueness on the spring-dependent descriptor entries
};
// the config values the agents plan reads: the run's seed, the [agents] section and the run's physics
struct AgentsDef {
  uint64_t seed = 0;
  config::RunConfig::Agents agents;
  sim::RunPhysics physics;  // run.contact, run.precision
};
AgentsDef agents_def(const config::RunConfig& cfg);

// the stage as a plan: one round per generation (0 .. agents.generations), one item per agent trained (created
// or mutated on the master); the master's selection is the round's reduction, and finish() records the final
// population. `population`: the master's survivors of the last committed generation (empty for a new run and on
// the other ranks)
std::unique_ptr<Plan> make_agents_plan(const AgentsDef& def, const AgentsSpec& spec,
                                       std::vector<evo::Individual> population);

// the name of generation g's group: <group>/gen_NNN
std::string gen_name(const std::string& group, int g);

// runs (or resumes) one population's evolution into spec.group (the agents stage's runner with the defaults)
void run_agents(Driver& driver, const AgentsDef& def, const AgentsSpec& spec);

}  // namespace divcoll::stages
