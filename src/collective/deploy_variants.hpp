// the deployment's readings of the paper that a study varies (deploy.uniform_agents,
// deploy.feature_placement, deploy.early_step), in one place for deploy, the analysis stage and export
#pragma once

#include <utility>
#include <vector>

#include "collective/builders.hpp"
#include "io/config.hpp"
#include "sim/engine.hpp"

namespace divcoll::collective {

// the (posterior, anterior) agents of uniform deployment pair q < deploy.pairs: (i, i) with i = q, or
// i = connectors.batch_pairs + q when deploy.uniform_agents = held_out
std::vector<std::pair<int, int>> deploy_uniform_pairs(const io::RunConfig& cfg);

// how much further ahead than a collective's the features of agent `a` deployed alone start
// (deploy.feature_placement: front 0, pair_mean (w + 0.05)/2, rear w + 0.05, w = a's body length)
double alone_feature_offset(const io::RunConfig& cfg, const Agent& a);

// travel in u at `step` of a run of a scene of `masses` masses made with RunOptions::record, computed as the engine computes its final
// travel (mean x at step − mean x at 0), so a run of `step` steps has this travel bit for bit; NaN unless ok
double travel_at(const sim::RunResult& r, int masses, int step);

}  // namespace divcoll::collective
