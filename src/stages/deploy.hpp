// the deployment stage (SPEC §7.1–7.2): every agent alone, and the eight collective types (connector
// kind trained {weak, strong} × {uniform, diverse}, deployed on {uniform, diverse} pairs), in every
// environment of deploy.environments, without learning. One round of the task farm per environment,
// a checkpoint after each.
//
// Run file (group /deploy; attributes status, environments, types, references, envs_done):
//   diverse_pairs            (pairs × 2)            the fixed list of diverse deployment pairs
//   agents/travel_bl, travel_u, status              (E × population)
//   agents/travel_bl_early, collectives/travel_bl_early  the same at deploy.early_step (only when > 0; NaN unless ok)
//   collectives/travel_bl, travel_u, status         (E × types × replicates × pairs)
//   references/travel_bl, travel_u, status, travel_bl_early  (E × 2·3 × pairs)  with deploy.references: the reference
//                            connectors free, passive, follower (src/collective/references.hpp), each on uniform and on
//                            diverse pairs (attribute references), items after the trained types'
//   hidden/<type>/states     (E × replicates × pairs × K × 32, float32)  connector hidden states (SPEC §8.2)
//   hidden/<type>/index      (E × replicates × pairs × K)  which: step · 5 + connector spring
//     for the weak connectors deployed as trained (weak_uniform@uniform, weak_diverse@diverse); K =
//     ceil(deploy.hidden_subsample / pairs) states per episode, drawn from the episode's own stream
//     (seed, 3001, item), so at most hidden_subsample per (type, replicate, environment); NaN if not ok
// status: 0 ok, 1 nan, 2 unstable; travel is NaN unless ok, and no summary averages over NaN.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "collective/builders.hpp"
#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages {

inline constexpr uint64_t kDeployStage = config::stage_stream("deploy");

// the collective types deployed: every trained kind on uniform and on diverse pairs
struct DeployTypes {
  std::vector<std::string> names;                          // <kind>@uniform, <kind>@diverse
  std::vector<std::vector<std::vector<double>>> weights;   // [type][replicate] → params
  std::vector<collective::Tether> tethers;                 // [type]
  std::vector<bool> diverse;                               // [type]: on diverse pairs
};

// the config values the deployment reads: the run's seed, the [deploy] section, from [connectors] the replicates and
// (deploy.uniform_agents = held_out) batch_pairs, analysis.familiarity_on (whether the connectors' inputs are kept
// beside their hidden states) and the run's physics
struct DeployDef {
  uint64_t seed = 0;
  config::RunConfig::Deploy deploy;
  config::RunConfig::Connectors connectors;
  config::RunConfig::Analysis analysis;
  sim::RunPhysics physics;  // run.contact, run.precision
};
DeployDef deploy_def(const config::RunConfig& cfg);

// the deployment as a plan: one round per environment, one item per episode (every agent alone, then every
// collective type × replicate × pair); the rows of round e are row e of every dataset. It keeps a reference to
// `agents`, which must outlive it
std::unique_ptr<Plan> make_deploy_plan(const DeployDef& def, const std::vector<morph::Agent>& agents,
                                       DeployTypes types);

}  // namespace divcoll::stages
