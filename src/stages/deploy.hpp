// the deployment stage (SPEC §7.1–7.2): every agent alone, and the eight collective types (connector
// kind trained {weak, strong} × {uniform, diverse}, deployed on {uniform, diverse} pairs), in every
// environment of deploy.environments, without learning. One round of the task farm per environment,
// a checkpoint after each.
//
// Run file: group /deploy, every dataset with its shape, unit and doc in the run-file schema (src/io/run_file.cpp;
// `divcoll schema`, mpi/README.md "Run-file layout"). The references rows (deploy.references) are the reference
// connectors of src/collective/references.hpp, each on uniform and on diverse pairs, as items after the trained
// types'. The hidden states are kept for the weak connectors deployed as trained (weak_uniform@uniform,
// weak_diverse@diverse): K = ceil(deploy.hidden_subsample / pairs) states per episode, drawn from the episode's own
// stream (seed, 3001, item), so at most hidden_subsample per (type, replicate, environment). Travel is NaN unless
// the episode's status is ok, and no summary averages over NaN.
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
