// what a tether does to each agent of a pair: the impulse and work its five springs give the posterior and the
// anterior over an episode (sim::RunOptions::record_tether), beside each agent's own travel in the pair and alone.
//
// The springs' forces are equal and opposite (SPEC §2 step 2), so the two impulses sum to zero and a tether moves
// the pair's centre of mass only through how it changes each agent's ground contact. These numbers say, per agent,
// which way the tether pushed it, how much work the tether did on it (positive: energy put in) and how far it went
// compared with walking alone from the same start.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "collective/builders.hpp"
#include "sim/engine.hpp"

namespace divcoll::collective {

// one pair episode with its tether's account; index 0 is the posterior (left, behind), 1 the anterior
struct TetherEffect {
  sim::Status status = sim::Status::ok;
  double pair_travel_bl = 0;               // the pair's centre of mass, in the two agents' mean body length
  std::array<double, 2> travel_bl{};       // each agent's own centre of mass in the pair, in its body length
  std::array<double, 2> impulse_x{};       // mass·u/s, the tether's horizontal impulse on each agent (they sum to 0)
  std::array<double, 2> work{};            // mass·u²/s², the work the tether's springs did on each agent
  double force_time = 0;                   // mass·u/s, Σ over the five springs of ∫|f| dt
};

// `posterior` left, `anterior` right, joined by the connector `params` with `tether`, for `steps` steps in `env`
TetherEffect tether_effect(sim::Simulator& sim, const Agent& posterior, const Agent& anterior,
                           const std::vector<double>& params, const Tether& tether, const std::string& env,
                           const sim::RunPhysics& physics, int steps);

}  // namespace divcoll::collective
