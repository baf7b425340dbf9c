// the specialists stage (SPEC §7.3): weak connectors trained on diverse pairs in each novel environment, then
// each deployed in its environment on the deployment stage's diverse pairs (an EpisodesPlan, stages/episodes.hpp)
//
// Run file, group /specialists (attributes status, environments = the novel ones, replicates, envs_done):
//   <env>/params (R × P_c), <env>/curve_u, curve_bl, nan_pairs (I × R)   as in /connectors
//   state/*                                                             the optimizer state
//   travel_bl, travel_u, status  (novel envs × R × deploy.pairs)  each specialist in its environment on
//                                                                 the deployment stage's diverse pairs,
//                                                                 one round (row) per environment
#pragma once

#include <cstdint>
#include <vector>

#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

inline constexpr uint64_t kSpecialistsStage = config::stage_stream("specialists");

// the config values the specialists read: the run's seed, the [specialists] section, the [connectors] section
// (their training and springs), the [deploy] section (the novel environments, the deployment's diverse pairs and
// episode length) and the run's physics
struct SpecialistsDef {
  uint64_t seed = 0;
  config::RunConfig::Specialists specialists;
  config::RunConfig::Connectors connectors;
  config::RunConfig::Deploy deploy;
  sim::RunPhysics physics;  // run.contact, run.precision
};
SpecialistsDef specialists_def(const config::RunConfig& cfg);

}  // namespace divcoll::stages
