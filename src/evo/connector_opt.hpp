// connector optimisation beyond a constant-rate Adam: what the field does for exploding or chaotic
// backpropagation through time, each a [connectors] key whose default is the plain method.
//
// - a decaying rate (lr_schedule: cosine or exponential to lr·lr_final at the last iteration);
// - keep-best: the weights scored best on a fixed validation batch, instead of the last ones;
// - truncated backpropagation (bptt_window, sim::RunOptions::grad_window);
// - per-pair clipping (clip = per_pair): each pair's gradient scaled down to clip_norm before the batch mean
//   (ProbeSum::pair_clip), instead of clipping only the mean; works with the plain and the extended method;
// - gradient averaging (grad_samples, grad_sigma): Gaussian smoothing of the batch objective, the gradient
//   averaged at antithetic perturbations θ ± σε of the weights on the same batch;
// - black-box controls, no gradient: CMA-ES (pagmo2's cmaes) over the 1473 weights, fitness = −mean batch
//   travel; and es, the antithetic evolution strategy of Salimans et al. (2017): popsize/2 pairs θ ± σε, centred
//   ranks of their batch travel, the search gradient stepped by Adam. pagmo's cmaes forms the n×n product B·D
//   for every candidate (O(popsize·n³) per generation, ~8 s of one core per connector and iteration at
//   n = 1473), so the measurements use es; cmaes stays for smaller problems and as the library's reference.
//
// The optimizer is ask/tell: ask(it) names the weight vectors ("probes") whose batch results it needs, the
// caller runs every probe on every pair of the batch (in any order, on any rank: results are placed by index
// and summed in pair order by the caller), and tell(it, ...) takes one step. No MPI here: the connectors stage
// farms the probes, `divcoll connector-opt` and the tests run them in a plain loop.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "collective/builders.hpp"
#include "collective/pairs.hpp"
#include "config/config.hpp"
#include "evo/optim.hpp"
#include "config/pipeline.hpp"

namespace divcoll::evo {

// the [connectors] keys the optimizer reads, taken from the section by opt_settings (the config's schema holds
// their defaults: opt_settings(config::default_config().connectors)); a test or a command may then change them
struct OptSettings {
  std::string optimizer;    // adam | normalized | cmaes | es
  double lr{}, clip_norm{};
  std::string lr_schedule;  // constant | cosine | exponential
  double lr_final{};        // fraction of lr at the last iteration
  int bptt_window{};        // steps, 0 = full backpropagation
  int horizon_start{};      // horizon curriculum: training steps at the first iteration, 0 = none
  int horizon_ramp{};       // iterations to grow to the full episode
  int grad_samples{};       // gradients averaged per step
  double grad_sigma{};      // sd of their weight perturbations
  bool keep_best{};         // return the validation-best weights
  int es_popsize{};         // cmaes / es candidates per iteration
  double es_sigma{};        // cmaes initial sd per weight; es perturbation sd per weight
  std::string clip;         // global | per_pair: clip_norm clips the batch mean or each pair's gradient
};
inline OptSettings opt_settings(const config::RunConfig::Connectors& c) {
  return {c.optimizer,     c.lr,           c.clip_norm,    c.lr_schedule, c.lr_final,   c.bptt_window, c.horizon_start,
          c.horizon_ramp,  c.grad_samples, c.grad_sigma,   c.keep_best,   c.es_popsize, c.es_sigma,    c.clip};
}
// the norm each pair's gradient is scaled down to before the batch sum: clip_norm with clip = per_pair, else 0
// (no per-pair clipping; ProbeSum::pair_clip)
inline double pair_clip(const OptSettings& s) { return s.clip == "per_pair" ? s.clip_norm : 0.0; }
// true if any key asks for more than the plain method (the connectors stage then trains through ConnectorOptimizer)
bool extended(const OptSettings& s);

// the learning rate of iteration it (0-based) of `iterations`: lr at it = 0, lr·lr_final at the last iteration
double scheduled_lr(const OptSettings& s, int it, int iterations);
// the training episode's steps at iteration `it` (0-based) of the horizon curriculum: horizon_start growing linearly
// to episode_steps over horizon_ramp iterations (rounded down), episode_steps without a curriculum
int training_steps(const OptSettings& s, int episode_steps, int it);

// every value finite (a gradient fit to step with)
inline bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// the mean over a batch of one probe's pair episodes (the caller sums in pair order)
struct ProbeResult {
  double travel_u = 0, travel_bl = 0;  // means over the ok pairs (NaN if none)
  int ok = 0, not_ok = 0;
  int bad_grad = 0;          // of not_ok: pairs whose episode was ok but whose gradient was not finite
  int redone = 0;            // pairs whose float gradient overflowed and that were run again in double
  std::vector<double> grad;  // mean d travel_u / d weights over the ok pairs (probes asked with grad)
};
// accumulates pair outcomes in pair order into a ProbeResult. A pair whose gradient is not finite (an episode that
// ran, but whose backward pass overflowed) counts as not ok, as an episode that failed does: one such pair would
// otherwise turn the connector's weights into NaN at the next step
struct ProbeSum {
  double pair_clip = 0;  // > 0: each ok pair's gradient is scaled down to this norm if longer before it is added
                         // (connectors.clip = per_pair); 0 = added as it is
  double su = 0, sb = 0;
  int ok = 0, not_ok = 0, bad_grad = 0, redone = 0;
  std::vector<double> g;
  void add(const collective::PairOutcome& o);
  ProbeResult mean() const;
};

struct Probe {
  std::vector<double> weights;
  bool grad = false;
};

class ConnectorOptimizer {
 public:
  // `seed`, `stream`: the slot's random stream (its items: config::kItem* in src/config/pipeline.hpp)
  ConnectorOptimizer(const OptSettings& s, std::vector<double> init, int iterations, uint64_t seed, uint64_t stream);
  ~ConnectorOptimizer();
  ConnectorOptimizer(ConnectorOptimizer&&) noexcept;
  ConnectorOptimizer& operator=(ConnectorOptimizer&&) noexcept;

  // the probes of iteration it, each to be run on the whole training batch
  std::vector<Probe> ask(int it);
  // one step from the probes' results (same order as ask); `validation` = the mean validation travel of
  // current() before this step (NaN when keep_best is off)
  void tell(int it, const std::vector<ProbeResult>& results, double validation);
  // after the last tell: the validation score of the final weights (keep_best)
  void finish(double validation);

  // the current point: the weights (gradient methods) or the search distribution's mean (cmaes)
  const std::vector<double>& current() const { return params_; }
  // the weights to keep: the validation-best ones with keep_best, else current()
  const std::vector<double>& result() const;
  // the batch travel reported for iteration it's curve: at the weights (mean over the probes), BL and u
  double curve_u = 0, curve_bl = 0;
  int curve_not_ok = 0;

  // keep-best bookkeeping: best validation score, the iteration whose weights scored it (I = the final ones)
  double best_score() const { return best_score_; }
  int best_iteration() const { return best_it_; }

  // checkpoint state: every vector the next step depends on (gradient methods: weights, Adam moments, best
  // weights; cmaes: the fitness of every candidate so far, replayed on restore), and scalars
  struct State {
    std::vector<double> params, m, v, best_params, es_fitness;
    double best_score = 0;
    int best_it = -1;
  };
  State state() const;
  // restores the state after `done` iterations (cmaes: replays asks and tells from the stored fitness)
  void restore(const State& st, int done);

  const OptSettings& settings() const { return s_; }

 private:
  struct Es;
  OptSettings s_;
  int iterations_;
  uint64_t seed_, stream_;
  std::vector<double> params_, best_params_;
  double best_score_;
  int best_it_ = -1;
  evo::Adam adam_;
  std::vector<std::vector<double>> eps_;  // this iteration's perturbations (grad_samples > 1)
  std::unique_ptr<Es> es_;
  std::vector<double> es_log_;  // fitness of every cmaes candidate so far, iteration-major
  void offer(int it, double validation);
};

// the pairs of a slot's fixed validation batch (keep_best): uniform kinds the clones of agents batch_pairs,
// batch_pairs + 1, ... (mod population), diverse kinds `n` random pairs from item 2000000 of the slot's stream
std::vector<std::pair<int, int>> validation_pairs(bool diverse, int n, int batch_pairs, int population, uint64_t seed,
                                                  uint64_t stream);

// a training run in a plain loop, one process (the `connector-opt` command and the tests): every slot option
// of the stage, curves per iteration, validation travel of current() before every step and after the last
struct PlainTrainResult {
  std::vector<double> params;                 // result()
  std::vector<double> last_params;            // current() after the last step
  std::vector<double> curve_bl, val_bl;       // per iteration (val_bl has iterations + 1 entries, NaN if off)
  int best_iteration = -1;
  long pair_episodes_grad = 0, pair_episodes_fwd = 0;  // the compute spent
};
struct PlainTrainSpec {
  collective::Tether tether{};  // stiffness, amplitude and dashpot from the run config (collective::tether), always given
  sim::RunPhysics physics{};  // the contact law and precision of every episode (config::run_physics), always given
  bool diverse = false;
  int iterations = 0, batch_pairs = 0, episode_steps = 1000, validation_pairs = 0;  // 0 = no validation
  uint64_t seed = 1, stream = 0;
};
PlainTrainResult train_plain(sim::Simulator& sim, const std::vector<morph::Agent>& agents, const OptSettings& s,
                             std::vector<double> init, const PlainTrainSpec& spec);

// one probe over a list of pairs in a plain loop (grad with the window of `s`), each episode under `physics`
ProbeResult run_probe(sim::Simulator& sim, const std::vector<morph::Agent>& agents,
                      const std::vector<std::pair<int, int>>& pairs, const std::vector<double>& weights, bool grad,
                      const collective::Tether& tether, const sim::RunPhysics& physics, int steps, int bptt_window,
                      double pair_clip = 0);

}  // namespace divcoll::evo
