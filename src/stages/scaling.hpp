// the scaling stage (SPEC §7.4): chains of N agents, uniform (N clones with a weak uniform-trained connector) and
// diverse (N distinct agents with a weak diverse-trained one), in every environment
//
// group /scaling (attributes status, environments, variants = uniform,diverse, envs_done):
//   sizes (S)                     chain sizes N
//   n<N>/diverse_agents           (R·draws × N) the agents of each diverse chain, heap order
//   travel_bl, travel_u, status   (E × S × 2 × R × draws); variant 0: N clones of agent `draw` with a weak
//                                 uniform-trained connector; 1: the diverse chain with a weak diverse-trained one
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "collective/builders.hpp"
#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

inline constexpr uint64_t kScalingStage = config::stage_stream("scaling");

// the config values the scaling chains read: the run's seed, the [scaling] section, deploy.environments, from
// [connectors] the replicates and the weak connector's springs, and the run's physics
struct ScalingDef {
  uint64_t seed = 0;
  config::RunConfig::Scaling scaling;
  config::RunConfig::Deploy deploy;
  config::RunConfig::Connectors connectors;
  sim::RunPhysics physics;  // run.contact, run.precision
};
ScalingDef scaling_def(const config::RunConfig& cfg);

// the chains as a plan: one round per environment, one item per chain (size × variant × replicate × draw).
// `weights`: the weak uniform-trained replicates, then the weak diverse-trained ones. It keeps a reference to
// `agents`, which must outlive it
std::unique_ptr<Plan> make_scaling_plan(const ScalingDef& def, const std::vector<morph::Agent>& agents,
                                        std::vector<std::vector<double>> weights);

}  // namespace divcoll::stages
