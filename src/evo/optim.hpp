// the optimizers of the project, one home: Adam on a flat parameter vector with global-norm gradient
// clipping (SPEC §6.4; the agents' gd_rule = adam uses it without clipping), and the normalized step.
// Both descend a loss; an ascent on a reward passes the negated gradient. (PaCMAP has its own Adam variant,
// ANALYSIS.md §1.9, with ε inside the bias correction: analysis/pacmap.*.)
#pragma once

#include <limits>
#include <vector>

namespace divcoll::evo {

struct Adam {
  std::vector<double> m, v;  // moments, same size as the parameters (zeros when empty)
  // one step of descent on `loss_grad`, t = 1, 2, ... the step number; the gradient is first scaled down
  // to norm clip_norm if longer (no clipping with the default)
  void step(std::vector<double>& params, std::vector<double> loss_grad, double lr,
            double clip_norm = std::numeric_limits<double>::infinity(), int t = 1);
};

// the normalized alternative: θ ← θ − lr·g/‖g‖ (no step when g = 0)
void normalized_step(std::vector<double>& params, const std::vector<double>& loss_grad, double lr);

}  // namespace divcoll::evo
