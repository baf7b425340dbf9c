// pairs for connector training and deployment (SPEC §6.4, §7.2): which pairs, one pair's episode with
// the gradient of its travel w.r.t. the connector weights (the optimizer: evo/optim.hpp)
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "collective/builders.hpp"
#include "common/rng.hpp"
#include "sim/engine.hpp"

namespace divcoll::collective {

// (posterior, anterior) agent indices: agent i with its clone for i < n
std::vector<std::pair<int, int>> uniform_pairs(int n);
// n ordered pairs of two different agents out of `population`, drawn from rng
std::vector<std::pair<int, int>> random_pairs(Rng& rng, int population, int n);

struct PairOutcome {
  double travel_u = 0;         // u, centre-of-mass displacement (NaN unless ok)
  double travel_bl = 0;        // travel_u / mean body length of the two agents
  sim::Status status = sim::Status::ok;
  std::vector<double> grad;    // d travel_u / d connector params (with grad; zeros unless ok)
  bool redone_in_double = false;  // float networks: their gradient overflowed, so the episode ran again in double
};

// Each episode runs under a run's physics: the overloads with a step count take it whole (sim::RunPhysics), those
// with every option of the run take the contact law and find the precision in `opt` (RunOptions::float_networks;
// RunPhysics::options() makes options in the run's precision).

// one pair episode: `posterior` left, `anterior` right, joined by the connector `params`
PairOutcome run_pair(sim::Simulator& sim, const Agent& posterior, const Agent& anterior,
                     const std::vector<double>& params, const Tether& tether, const std::string& env,
                     const sim::RunPhysics& physics, int steps, bool grad);

// the same with every option of the run (e.g. record_hidden); `full` (if given) receives the whole result
PairOutcome run_pair(sim::Simulator& sim, const Agent& posterior, const Agent& anterior,
                     const std::vector<double>& params, const Tether& tether, const std::string& env,
                     sim::ContactLaw law, const sim::RunOptions& opt, sim::RunResult* full);

// a chain of agents in heap order (agent 0 front-most), one connector for all: travel of the whole chain's
// centre of mass in u and in mean body lengths of its agents (no gradient)
PairOutcome run_chain(sim::Simulator& sim, const std::vector<const Agent*>& agents, const std::vector<double>& params,
                      const Tether& tether, const std::string& env, const sim::RunPhysics& physics, int steps);

// one agent alone: travel in u and BL
PairOutcome run_alone(sim::Simulator& sim, const Agent& a, const std::string& env, const sim::RunPhysics& physics,
                      int steps);
// the same with every option of the run (e.g. record); `full` (if given) receives the whole result
PairOutcome run_alone(sim::Simulator& sim, const Agent& a, const std::string& env, sim::ContactLaw law,
                      const sim::RunOptions& opt, sim::RunResult* full, double feature_offset = 0);

}  // namespace divcoll::collective
