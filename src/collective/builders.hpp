// scenes of agents, pairs and chains (SPEC §4.1, §6.1, §6.2, §7.4), shared by the CLI, the tests,
// the benchmark and the later pipeline stages
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/rng.hpp"
#include "morph/agent.hpp"
#include "sim/engine.hpp"
#include "sim/scene.hpp"

namespace divcoll::collective {

// the agent type is morphology's (morph/agent.hpp); the code in namespace collective (collective/, evo/connector_opt)
// names it, its anchors and its body length through these
using morph::Agent;
using morph::Anchors;
using morph::body_length;

// the springs of one connector (SPEC §6.2): all 5 get this stiffness, amplitude and dashpot. A run's come from its
// config (collective::tether, strength_tether: connectors.weak_stiffness or strong_stiffness, amplitude, damping),
// whose schema (config/config.cpp) is the one home of their defaults, the paper reading's 5000 / 30000 and 0.6
struct Tether {
  double stiffness = 0;  // force/u (per unit mass)
  double amplitude = 0;  // fraction of its rest length a spring's target length moves (0 = passive)
  double damping = 0;    // dashpot c_s, 1/s (SPEC §2.2; 0 = SPEC §6.2; connectors.damping)
};

// u, between a posterior's max x and its anterior's min x in a pair or a chain (SPEC §6.2, §7.4)
inline constexpr double kAgentGap = 0.05;

// a random valid agent with a freshly initialised controller
Agent random_agent(Rng& rng, const sim::Constants& c = {});
// an agent of the given body and spring genotypes at its lattice positions, with a fresh controller
Agent make_agent(uint32_t cells, uint32_t springs, Rng& rng, const sim::Constants& c = {});

// Every scene below is placed in a named built-in environment under the contact law `law` (the run's: sim::RunPhysics,
// config::run_physics), which the scene then carries (sim::Environment::contact).

// an agent alone in the named built-in environment, its lowest mass at y = 0 and min x = 0
// feature_offset: the environment's features start this much further ahead (deploy.feature_placement)
sim::Scene agent_scene(const Agent& a, const std::string& env, sim::ContactLaw law, const sim::Constants& c = {},
                       double feature_offset = 0);

// SPEC §6.1: anchors from the agent's own 1000-step run on flat ground, under the run's physics
Anchors compute_anchors(const Agent& a, const sim::RunPhysics& physics, const sim::Constants& c = {}, int steps = 1000);

// SPEC §6.2: posterior P (left, scene agent 0) and anterior A (right, scene agent 1, min x = P's max x + kAgentGap)
// joined by one connector with the given springs; both agents need anchors
sim::Scene pair_scene(const Agent& posterior, const Agent& anterior, const std::vector<double>& connector_params,
                      const Tether& tether, const std::string& env, sim::ContactLaw law, const sim::Constants& c = {});

// SPEC §7.4: a chain of agents in binary-tree heap order: agent 0 is front-most, agents 2k+1 and 2k+2 hang
// behind agent k (same x, overlapping); connector k−1 joins child k (posterior) to its parent (anterior)
sim::Scene chain_scene(const std::vector<const Agent*>& agents, const std::vector<double>& connector_params,
                       const Tether& tether, const std::string& env, sim::ContactLaw law, const sim::Constants& c = {});

}  // namespace divcoll::collective
