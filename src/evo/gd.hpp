// gradient descent on one agent (SPEC §4.4): controller weights and rest positions, the latter through
// both x(0) and the rest lengths, with the position constraints
#pragma once

#include <string>
#include <vector>

#include "config/config.hpp"
#include "morph/agent.hpp"
#include "evo/optim.hpp"
#include "sim/engine.hpp"

namespace divcoll::evo {

// how the parameters step each epoch
enum class GdRule {
  paper,      // θ ← θ + step·g/‖g‖ (ascent on travel), the last parameters are kept
  keep_best,  // the same steps, but the best parameters seen are kept (default: see configs/README.md, measured)
  adam,       // Adam on θ with learning rate adam_lr; the best parameters seen are kept
};
GdRule gd_rule_from(const std::string& name);  // "paper", "keep_best", "adam"; InputError otherwise
const char* gd_rule_name(GdRule r);

// the [agents] keys gradient descent reads, taken from the section by gd_options (the config's schema holds their
// defaults: gd_options(config::default_config().agents)); a test or a command may then change them
struct GdOptions {
  int epochs{};                    // gradient evaluations and updates
  int steps{};                     // steps per episode on flat ground
  GdRule rule{};
  double step{};                   // normalized step of the weights
  double adam_lr{};
  bool rest_moves{};               // whether rest positions are trained
  double rest_move_max{};          // u, largest move of any mass per epoch
  double rest_length_min{};        // × morph::kSpacing (0.05 u)
  double rest_length_max{};        // × morph::kSpacing
};
GdOptions gd_options(const config::RunConfig::Agents& a);

struct TrainResult {
  double travel_u = 0;             // travel of the kept parameters, u
  double fitness_bl = 0;           // travel_u / body length
  sim::Status status = sim::Status::ok;
  std::vector<double> curve_u;     // travel at each evaluation, epochs + 1 values (fewer if training stopped)
  // the first epoch whose gradient (of the weights or the rest positions) was not finite though its episode
  // ran: training stopped there, before any step from it, as after an episode that was not ok; -1: none
  int nonfinite_gradient_epoch = -1;
};

// body length of an agent (max x − min x of its rest positions), u
using morph::body_length;

// the gradient of travel w.r.t. the rest positions (11×2) from a graded run of agent_scene(a, "flat"):
// through x(0), through the rest lengths, and through the shift that keeps the lowest mass at y = 0
std::vector<double> rest_gradient(const morph::Agent& a, const sim::RunResult& r);

// trains `a` in place on flat ground under the run's `physics` and returns its fitness; `sim` is reused workspace
TrainResult train_agent(morph::Agent& a, const GdOptions& opt, const sim::RunPhysics& physics, sim::Simulator& sim);

// one epoch's update of `a` from the gradient of travel w.r.t. its weights (`g_params`) and rest positions
// (`g_rest`, 11×2), by opt.rule (`adam` holds Adam's moments, `epoch` counts from 0); returns false and leaves
// `a` untouched if either gradient has a value that is not finite
bool step_agent(morph::Agent& a, const std::vector<double>& g_params, const std::vector<double>& g_rest,
                const GdOptions& opt, Adam& adam, int epoch);

// moves rest positions by `delta` (11×2) if every rest length stays within the bounds (halving the move
// up to 4 times otherwise), then shifts so that min x = min y = 0; returns whether it moved
bool move_rest_positions(morph::Agent& a, const std::vector<double>& delta, const GdOptions& opt);

}  // namespace divcoll::evo
