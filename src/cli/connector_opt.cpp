// divcoll connector-opt: one connector training per kind and replicate with every [connectors] key (optimizer,
// schedule, keep-best, truncated backpropagation, gradient averaging, CMA-ES), in one process on a run file's
// agents, then the trained pairs and their agents alone on flat at several episode lengths. The
// connectors stage trains the same way over MPI; this command is the small experiment behind
// postprocess/gallery/science_connector_optimisation.md.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "cli/commands.hpp"
#include "evo/connector_opt.hpp"
#include "collective/deploy_variants.hpp"
#include "collective/references.hpp"
#include "common/check.hpp"
#include "common/rng.hpp"
#include "config/config.hpp"
#include "io/h5.hpp"
#include "morph/body.hpp"
#include "config/pipeline.hpp"
#include "io/run_read.hpp"

namespace divcoll::cli {

int connector_opt(const ConnectorOptArgs& a) {
  const std::string curves_path = a.out + "_curves.csv", summary_path = a.out + "_summary.csv";
  check_output_path(curves_path, a.force);
  check_output_path(summary_path, a.force);
  std::vector<int> eval_steps;
  {
    std::stringstream ss(a.eval_steps);
    std::string item;
    while (std::getline(ss, item, ',')) {
      std::stringstream is(item);
      int v = 0;
      DIVCOLL_THROW_UNLESS(is >> v && is.eof() && v >= 1, "--eval-steps: '" << item << "' is not a step count");
      eval_steps.push_back(v);
    }
  }
  const RunAgents ra = load_run_agents(a.run, a.overrides);
  const config::RunConfig& cfg = ra.cfg;
  const std::vector<morph::Agent>& agents = ra.agents;
  const int pop = static_cast<int>(agents.size());
  const auto& C = cfg.connectors;
  const evo::OptSettings os = evo::opt_settings(C);
  DIVCOLL_THROW_UNLESS(a.eval_pairs <= pop, "--eval-pairs " << a.eval_pairs << " is more than the population");

  std::ofstream curves(curves_path), summary(summary_path);
  DIVCOLL_THROW_UNLESS(curves && summary, "cannot write " << curves_path << " / " << summary_path);
  curves << "label,kind,replicate,iteration,curve_bl,val_bl\n";
  summary << "label,kind,replicate,weights,best_iteration,steps,pairs_bl,alone_bl,not_ok,grad_episodes,fwd_episodes,seconds\n";
  sim::Simulator sim;
  const int R = C.replicates;
  for (size_t k = 0; k < C.kinds.size(); ++k) {
    const std::string& kind = C.kinds[k];
    const bool diverse = config::connector_kind(kind).diverse;
    const collective::Tether stiff = collective::tether(C, kind);
    std::vector<std::pair<int, int>> eval;
    if (diverse) {
      Rng rng = make_rng(cfg.run.seed, config::stage_stream("deploy"), 0);  // the deployment's diverse pairs
      eval = collective::random_pairs(rng, pop, a.eval_pairs);
    } else {
      eval = collective::uniform_pairs(a.eval_pairs);
    }
    for (int r = 0; r < R; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      const uint64_t stream = config::stage_stream("connectors") + k * R + r;  // the connectors stage's slot stream
      Rng wr = make_rng(cfg.run.seed, stream, config::kItemInitialWeights);
      evo::PlainTrainSpec spec{stiff,        ra.physics,      diverse,           C.iterations, C.batch_pairs,
                                      C.episode_steps, C.validation_pairs, cfg.run.seed, stream};
      const evo::PlainTrainResult tr =
          evo::train_plain(sim, agents, os, collective::initial_connector_params(C, stiff.amplitude, wr), spec);
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      for (size_t i = 0; i < tr.val_bl.size(); ++i)
        curves << a.label << ',' << kind << ',' << r << ',' << i << ','
               << (i < tr.curve_bl.size() ? tr.curve_bl[i] : NAN) << ',' << tr.val_bl[i] << '\n';
      // the kept weights, and with keep_best also the last ones
      std::vector<std::pair<std::string, const std::vector<double>*>> which = {{"kept", &tr.params}};
      if (C.keep_best) which.push_back({"last", &tr.last_params});
      for (int T : eval_steps) {
        double alone = 0;
        for (const auto& [p, q] : eval)
          alone += 0.5 * (collective::run_alone(sim, agents[p], "flat", ra.physics, T).travel_bl +
                          collective::run_alone(sim, agents[q], "flat", ra.physics, T).travel_bl);
        alone /= static_cast<double>(eval.size());
        for (const auto& [name, w] : which) {
          const evo::ProbeResult pr = evo::run_probe(sim, agents, eval, *w, false, stiff, ra.physics, T, 0);
          summary << a.label << ',' << kind << ',' << r << ',' << name << ',' << tr.best_iteration << ',' << T << ','
                  << pr.travel_bl << ',' << alone << ',' << pr.not_ok << ',' << tr.pair_episodes_grad << ','
                  << tr.pair_episodes_fwd << ',' << secs << '\n';
          std::printf("%s %s replicate %d, %s weights: %d steps: pairs %.3f BL, agents alone %.3f BL (best iteration %d, %.0f s)\n",
                      a.label.c_str(), kind.c_str(), r, name.c_str(), T, pr.travel_bl, alone, tr.best_iteration, secs);
        }
      }
      curves.flush(), summary.flush();
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace divcoll::cli
