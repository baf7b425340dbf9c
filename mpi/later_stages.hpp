// the stages after deployment (SPEC §7.3–7.5): specialists, scaling chains, graded diversity
#pragma once

#include <mpi.h>

#include <functional>

#include "config/config.hpp"
#include "io/h5.hpp"
#include "config/pipeline.hpp"

namespace divcoll::mpi {

inline constexpr uint64_t kSpecialistsStage = io::stage_stream("specialists");
inline constexpr uint64_t kScalingStage = io::stage_stream("scaling");
inline constexpr uint64_t kGradedStage = io::stage_stream("graded");

// Run file, group /specialists (attributes status, environments = the novel ones, replicates, envs_done):
//   <env>/params (R × P_c), <env>/curve_u, curve_bl, nan_pairs (I × R)   as in /connectors
//   state/*                                                             the optimizer state
//   travel_bl, travel_u, status  (novel envs × R × deploy.pairs)  each specialist in its environment on
//                                                                 the deployment stage's diverse pairs,
//                                                                 one round (row) per environment
// group /scaling (attributes status, environments, variants = uniform,diverse, envs_done):
//   sizes (S)                     chain sizes N
//   n<N>/diverse_agents           (R·draws × N) the agents of each diverse chain, heap order
//   travel_bl, travel_u, status   (E × S × 2 × R × draws); variant 0: N clones of agent `draw` with a weak
//                                 uniform-trained connector; 1: the diverse chain with a weak diverse-trained one
// group /graded (attributes status, environments, populations, shape_cells, shape_springs): per population
// same_shape (one body, evolved springs) and same_shape_springs (one body and spring genotype, trained
// controllers only), each with attributes status, diversity_sources and envs_done (its deployment's rounds):
//   agents/                    as /agents (gen_NNN, final), graded.population agents
//   connectors/weak_diverse/   params, curve_* (as /connectors); connectors/state/*
//   diverse_pairs              (pairs × 2)
//   deploy/agents/travel_bl, travel_u, status   (E × graded.population)
//   deploy/pairs/travel_bl, travel_u, status    (E × R × pairs)

}  // namespace divcoll::mpi
