// the readings of the paper that a study varies in how collectives are built and deployed (connectors.amplitude,
// deploy.uniform_agents, deploy.feature_placement, deploy.early_step), in one place for the stages and commands
#pragma once

#include <string_view>
#include <utility>
#include <vector>

#include "collective/builders.hpp"
#include "config/config.hpp"
#include "sim/engine.hpp"

namespace divcoll::collective {

// the springs of a connector of `kind` (weak_uniform, weak_diverse, strong_uniform, strong_diverse) from the
// [connectors] section: the kind's stiffness (weak_stiffness or strong_stiffness; 0 with follower), amplitude
// and damping
Tether tether(const config::RunConfig::Connectors& connectors, std::string_view kind);
// the same for a strength alone (weak or strong), as `divcoll scene --connector` names it
Tether strength_tether(const config::RunConfig::Connectors& connectors, std::string_view strength);

// the (posterior, anterior) agents of uniform deployment pair q < deploy.pairs: (i, i) with i = q, or
// i = connectors.batch_pairs + q when deploy.uniform_agents = held_out
std::vector<std::pair<int, int>> deploy_uniform_pairs(const config::RunConfig::Deploy& deploy,
                                                      const config::RunConfig::Connectors& connectors);

// how much further ahead than a collective's the features of agent `a` deployed alone start
// (deploy.feature_placement: front 0, pair_mean (w + kAgentGap)/2, rear w + kAgentGap, w = a's body length)
double alone_feature_offset(const config::RunConfig::Deploy& deploy, const Agent& a);

// travel in u at `step` of a run of a scene of `masses` masses made with RunOptions::record, computed as the engine computes its final
// travel (mean x at step − mean x at 0), so a run of `step` steps has this travel bit for bit; NaN unless ok
double travel_at(const sim::RunResult& r, int masses, int step);

}  // namespace divcoll::collective
