// divcoll gd-compare: the gradient rules of SPEC §4.4 measured on the same random agents (same seeds)
#include <cmath>
#include <cstdio>
#include <vector>

#include "cli/commands.hpp"
#include "collective/builders.hpp"
#include "evo/gd.hpp"

namespace divcoll::cli {

int gd_compare(const GdCompareArgs& a) {
  struct Variant {
    const char* name;
    evo::GdRule rule;
    double step;
  };
  const Variant variants[] = {{"paper, step 0.16", evo::GdRule::paper, 0.16},
                              {"paper, step 0.04", evo::GdRule::paper, 0.04},
                              {"keep_best, step 0.16", evo::GdRule::keep_best, 0.16},
                              {"adam, lr 0.003", evo::GdRule::adam, 0.003},
                              {"adam, lr 0.01", evo::GdRule::adam, 0.01},
                              {"adam, lr 0.03", evo::GdRule::adam, 0.03}};
  std::printf("# gradient rules on %d random agents, %d epochs of %d steps on flat (fitness in BL)\n\n", a.agents,
              a.epochs, a.steps);
  std::printf("| rule | mean final | sd | min | max | mean drop from best seen | largest drop |\n|---|---|---|---|---|---|---|\n");
  for (const Variant& v : variants) {
    evo::GdOptions opt = evo::gd_options(config::default_config().agents);
    opt.epochs = a.epochs;
    opt.steps = a.steps;
    opt.rule = v.rule;
    opt.step = v.step;
    opt.adam_lr = v.step;
    sim::Simulator sim;
    std::vector<double> fit;
    double drop_sum = 0, drop_max = 0;
    for (int i = 0; i < a.agents; ++i) {
      Rng rng = make_rng(a.seed, 77, i);
      morph::Agent ag = collective::random_agent(rng);
      const evo::TrainResult r = evo::train_agent(ag, opt, sim::RunPhysics{}, sim);  // the spec's: coulomb, double
      fit.push_back(r.fitness_bl);
      // how far below the best evaluation the curve ended (the noise of the rule)
      double best = -1e300;
      for (double c : r.curve_u) best = std::max(best, c);
      const double drop = (best - r.curve_u.back()) / evo::body_length(ag);
      drop_sum += drop;
      drop_max = std::max(drop_max, drop);
    }
    double mean = 0, sd = 0, lo = 1e300, hi = -1e300;
    for (double f : fit) mean += f / fit.size(), lo = std::min(lo, f), hi = std::max(hi, f);
    for (double f : fit) sd += (f - mean) * (f - mean) / (fit.size() - 1);
    std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", v.name, mean, std::sqrt(sd), lo, hi,
                drop_sum / a.agents, drop_max);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace divcoll::cli
