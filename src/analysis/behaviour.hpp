// behaviour of one agent in a recorded episode (SPEC §8.1): its masses' positions relative to its centre of
// mass, every `every`-th step — the series that the DTW adversity compares
#pragma once

#include <vector>

#include "sim/engine.hpp"
#include "sim/scene.hpp"

namespace divcoll::analysis {

// frames at steps 0, every, 2·every, ... ≤ T of agent `agent` of `scene`, from `run` recorded with
// RunOptions::record; row f holds (x, y) of the agent's 11 masses minus the agent's mass-weighted centre,
// in the agent's own mass order: frames × 22, row-major. Empty when the run is not ok.
std::vector<double> agent_behaviour(const sim::Scene& scene, const sim::RunResult& run, int agent, int every);

// features per frame of agent_behaviour
inline constexpr int kBehaviourFeatures = 2 * sim::kAgentMasses;

}  // namespace divcoll::analysis
