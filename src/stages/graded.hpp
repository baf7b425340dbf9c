// the graded-diversity stage (SPEC §7.5): two populations of the main population's commonest body, one with
// evolved springs (same_shape) and one with its commonest spring genotype too (same_shape_springs: controllers
// only), each evolved (stages/agents.hpp), given weak connectors trained on its diverse pairs
// (stages/connectors.hpp) and deployed alone and in pairs in every environment (stages/episodes.hpp)
//
// group /graded (attributes status, environments, populations, shape_cells, shape_springs): per population
// same_shape (one body, evolved springs) and same_shape_springs (one body and spring genotype, trained
// controllers only), each with attributes status, diversity_sources and envs_done (its deployment's rounds):
//   agents/                    as /agents (gen_NNN, final), graded.population agents
//   connectors/weak_diverse/   params, curve_* (as /connectors); connectors/state/*
//   diverse_pairs              (pairs × 2)
//   deploy/agents/travel_bl, travel_u, status   (E × graded.population)
//   deploy/pairs/travel_bl, travel_u, status    (E × R × pairs)
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "collective/builders.hpp"
#include "config/config.hpp"
#include "config/pipeline.hpp"
#include "evo/evolution.hpp"
#include "stages/agents.hpp"
#include "stages/episodes.hpp"

namespace divcoll::stages {

inline constexpr uint64_t kGradedStage = config::stage_stream("graded");

// the graded populations, in order
inline constexpr const char* kGradedPopulations[2] = {"same_shape", "same_shape_springs"};

// the most common body of the main population (ties: the lowest genotype), and the most common spring genotype
// among its agents of that body
struct GradedShape {
  uint32_t cells = 0, springs = 0;
};
GradedShape graded_shape(const std::vector<evo::Individual>& main);

// the config values the graded populations read: the run's seed, the [graded] section, the [agents] section they
// start from, the [connectors] section (their weak diverse connectors' training), the [deploy] section and the
// run's physics
struct GradedDef {
  uint64_t seed = 0;
  config::RunConfig::Graded graded;
  config::RunConfig::Agents agents;
  config::RunConfig::Connectors connectors;
  config::RunConfig::Deploy deploy;
  sim::RunPhysics physics;  // run.contact, run.precision
};
GradedDef graded_def(const config::RunConfig& cfg);

// population v's evolution: its config values (graded.population agents, one body, rest positions fixed; for
// v = 1 one spring genotype and no evolution) and where it goes
std::pair<AgentsDef, AgentsSpec> graded_agents(const GradedDef& def, int v, GradedShape shape);

// population v's deployment as a plan: agents alone and its diverse `pairs` with its weak diverse-trained
// connectors (`weights`, one per replicate) in every environment. It keeps a reference to `agents`
std::unique_ptr<EpisodesPlan> make_graded_deploy_plan(const GradedDef& def, int v,
                                                      const std::vector<morph::Agent>& agents,
                                                      std::vector<std::vector<double>> weights,
                                                      std::vector<std::pair<int, int>> pairs);

}  // namespace divcoll::stages
