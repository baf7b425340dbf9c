#include "evo/connector_opt.hpp"

#include "common/dmath.hpp"
#include "evo/es_cmaes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "common/check.hpp"
#include "common/rng.hpp"

namespace divcoll::evo {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kBadFitness = 1e9;  // a cmaes candidate whose every pair episode failed

}  // namespace

struct ConnectorOptimizer::Es {
  std::unique_ptr<Cmaes> cmaes;
  std::vector<std::vector<double>> asked;
  int lambda = 0;
};

bool extended(const OptSettings& s) {
  return s.optimizer == "cmaes" || s.optimizer == "es" || s.lr_schedule != "constant" || s.bptt_window > 0 || s.grad_samples > 1 ||
         s.keep_best || s.horizon_start > 0;
}

int training_steps(const OptSettings& s, int episode_steps, int it) {
  if (s.horizon_start <= 0) return episode_steps;
  if (s.horizon_ramp <= 0) return s.horizon_start;
  if (it >= s.horizon_ramp) return episode_steps;
  return s.horizon_start + static_cast<int>(static_cast<int64_t>(episode_steps - s.horizon_start) * it / s.horizon_ramp);
}

double scheduled_lr(const OptSettings& s, int it, int iterations) {
  const double f = iterations > 1 ? static_cast<double>(it) / (iterations - 1) : 0.0;
  if (s.lr_schedule == "cosine") return s.lr * (s.lr_final + (1 - s.lr_final) * 0.5 * (1 + dmath::cos(std::numbers::pi * f)));
  if (s.lr_schedule == "exponential") return s.lr * dmath::pow(s.lr_final, f);
  DIVCOLL_DEMAND(s.lr_schedule == "constant");
  return s.lr;
}

void ProbeSum::add(const collective::PairOutcome& o) {
  redone += o.redone_in_double ? 1 : 0;
  if (o.status != sim::Status::ok || !std::isfinite(o.travel_u)) {
    ++not_ok;
    return;
  }
  if (!all_finite(o.grad)) {
    ++not_ok, ++bad_grad;
    return;
  }
  ++ok;
  su += o.travel_u;
  sb += o.travel_bl;
  if (!o.grad.empty()) {
    if (g.empty()) g.assign(o.grad.size(), 0.0);
    double scale = 1.0;
    if (pair_clip > 0) {
      double n2 = 0;
      for (double x : o.grad) n2 += x * x;
      const double n = std::sqrt(n2);
      if (n > pair_clip) scale = pair_clip / n;
    }
    if (scale == 1.0)
      for (size_t q = 0; q < g.size(); ++q) g[q] += o.grad[q];
    else
      for (size_t q = 0; q < g.size(); ++q) g[q] += o.grad[q] * scale;
  }
}

ProbeResult ProbeSum::mean() const {
  ProbeResult r;
  r.ok = ok, r.not_ok = not_ok, r.bad_grad = bad_grad, r.redone = redone;
  r.travel_u = ok ? su / ok : kNaN;
  r.travel_bl = ok ? sb / ok : kNaN;
  r.grad = g;
  if (ok)
    for (double& x : r.grad) x /= ok;
  return r;
}

ConnectorOptimizer::ConnectorOptimizer(const OptSettings& s, std::vector<double> init, int iterations, uint64_t seed,
                                       uint64_t stream)
    : s_(s), iterations_(iterations), seed_(seed), stream_(stream), params_(std::move(init)),
      best_score_(-std::numeric_limits<double>::infinity()) {
  adam_.m.assign(params_.size(), 0.0);
  adam_.v.assign(params_.size(), 0.0);
  if (s_.optimizer == "cmaes") {
    es_ = std::make_unique<Es>();
    es_->lambda = s_.es_popsize;
    Rng rng = make_rng(seed_, stream_, config::kItemCmaesSeed);
    const unsigned es_seed = static_cast<unsigned>(rng() >> 32);
    es_->cmaes = std::make_unique<Cmaes>(params_, es_->lambda, s_.es_sigma, es_seed);
  }
}
ConnectorOptimizer::~ConnectorOptimizer() = default;
ConnectorOptimizer::ConnectorOptimizer(ConnectorOptimizer&&) noexcept = default;
ConnectorOptimizer& ConnectorOptimizer::operator=(ConnectorOptimizer&&) noexcept = default;

std::vector<Probe> ConnectorOptimizer::ask(int it) {
  std::vector<Probe> probes;
  if (es_) {
    es_->asked = es_->cmaes->ask();
    for (const auto& x : es_->asked) probes.push_back({x, false});
    return probes;
  }
  if (s_.optimizer == "es") {
    // popsize/2 antithetic pairs θ ± σε, forward only
    eps_.clear();
    Rng rng = make_rng(seed_, stream_, config::kItemEsPerturbation + static_cast<uint64_t>(it));
    for (int j = 0; j < s_.es_popsize / 2; ++j) {
      std::vector<double> e(params_.size());
      for (double& x : e) x = normal(rng);
      std::vector<double> plus = params_, minus = params_;
      for (size_t q = 0; q < e.size(); ++q) plus[q] += s_.es_sigma * e[q], minus[q] -= s_.es_sigma * e[q];
      probes.push_back({std::move(plus), false});
      probes.push_back({std::move(minus), false});
      eps_.push_back(std::move(e));
    }
    return probes;
  }
  const int S = s_.grad_samples;
  if (S <= 1) return {{params_, true}};
  // antithetic pairs θ + σε, θ − σε (and θ itself when S is odd)
  eps_.clear();
  Rng rng = make_rng(seed_, stream_, config::kItemGradPerturbation + static_cast<uint64_t>(it));
  for (int j = 0; j < S / 2; ++j) {
    std::vector<double> e(params_.size());
    for (double& x : e) x = s_.grad_sigma * normal(rng);
    std::vector<double> plus = params_, minus = params_;
    for (size_t q = 0; q < e.size(); ++q) plus[q] += e[q], minus[q] -= e[q];
    probes.push_back({std::move(plus), true});
    probes.push_back({std::move(minus), true});
  }
  if (S % 2) probes.push_back({params_, true});
  return probes;
}

void ConnectorOptimizer::offer(int it, double validation) {
  if (!s_.keep_best || !std::isfinite(validation)) return;
  if (validation > best_score_) best_score_ = validation, best_it_ = it, best_params_ = params_;
}

void ConnectorOptimizer::tell(int it, const std::vector<ProbeResult>& results, double validation) {
  offer(it, validation);
  // the curve: the probes' mean batch travel (one probe: the travel at the weights)
  double su = 0, sb = 0;
  int n = 0;
  curve_not_ok = 0;
  for (const ProbeResult& r : results) {
    curve_not_ok += r.not_ok;
    if (r.ok == 0) continue;
    su += r.travel_u, sb += r.travel_bl, ++n;
  }
  curve_u = n ? su / n : kNaN;
  curve_bl = n ? sb / n : kNaN;

  if (es_) {
    std::vector<double> f;
    for (const ProbeResult& r : results) f.push_back(r.ok ? -r.travel_u : kBadFitness);
    es_log_.insert(es_log_.end(), f.begin(), f.end());
    es_->cmaes->tell(f);
    // the distribution's new mean, recombined as pagmo's cmaes does (log weights over the best λ/2)
    const int lam = es_->lambda, mu = lam / 2;
    std::vector<int> idx(lam);
    std::iota(idx.begin(), idx.end(), 0);
    std::stable_sort(idx.begin(), idx.end(), [&](int a, int b) { return f[a] < f[b]; });
    std::vector<double> w(mu);
    for (int i = 0; i < mu; ++i) w[i] = dmath::log(mu + 0.5) - dmath::log(i + 1.0);
    const double ws = std::accumulate(w.begin(), w.end(), 0.0);
    std::fill(params_.begin(), params_.end(), 0.0);
    for (int i = 0; i < mu; ++i)
      for (size_t q = 0; q < params_.size(); ++q) params_[q] += es_->asked[idx[i]][q] * (w[i] / ws);
    return;
  }
  if (s_.optimizer == "es") {
    // centred ranks of the batch travel (a failed probe ranks last), the search gradient
    // Σ_j (u(θ+σε_j) − u(θ−σε_j)) ε_j / (popsize·σ) of travel, and an Adam step on its negative
    const int n = static_cast<int>(results.size());
    std::vector<int> idx(n);
    std::iota(idx.begin(), idx.end(), 0);
    auto value = [&](int i) { return results[i].ok ? results[i].travel_u : -std::numeric_limits<double>::infinity(); };
    std::stable_sort(idx.begin(), idx.end(), [&](int a, int b) { return value(a) < value(b); });
    std::vector<double> u(n);
    for (int r = 0; r < n; ++r) u[idx[r]] = n > 1 ? static_cast<double>(r) / (n - 1) - 0.5 : 0.0;
    std::vector<double> g(params_.size(), 0.0);
    for (size_t j = 0; j < eps_.size(); ++j) {
      const double w = -(u[2 * j] - u[2 * j + 1]) / (n * s_.es_sigma);  // loss = −travel
      for (size_t q = 0; q < g.size(); ++q) g[q] += w * eps_[j][q];
    }
    adam_.step(params_, g, scheduled_lr(s_, it, iterations_), s_.clip_norm, it + 1);
    return;
  }
  // gradient methods: the mean gradient of the probes that had an ok pair; loss = −travel
  std::vector<double> g;
  int k = 0;
  for (const ProbeResult& r : results) {
    if (r.ok == 0) continue;
    if (g.empty()) g.assign(r.grad.size(), 0.0);
    for (size_t q = 0; q < g.size(); ++q) g[q] += r.grad[q];
    ++k;
  }
  if (k == 0) return;
  for (double& x : g) x = -x / k;
  const double lr = scheduled_lr(s_, it, iterations_);
  if (s_.optimizer == "adam")
    adam_.step(params_, g, lr, s_.clip_norm, it + 1);
  else
    evo::normalized_step(params_, g, lr);
}

void ConnectorOptimizer::finish(double validation) { offer(iterations_, validation); }

const std::vector<double>& ConnectorOptimizer::result() const {
  return s_.keep_best && best_it_ >= 0 ? best_params_ : params_;
}

ConnectorOptimizer::State ConnectorOptimizer::state() const {
  State st;
  st.params = params_;
  st.m = adam_.m;
  st.v = adam_.v;
  st.best_params = best_it_ >= 0 ? best_params_ : params_;
  st.es_fitness = es_log_;
  st.best_score = best_score_;
  st.best_it = best_it_;
  return st;
}

void ConnectorOptimizer::restore(const State& st, int done) {
  best_score_ = st.best_score;
  best_it_ = st.best_it;
  if (best_it_ >= 0) best_params_ = st.best_params;
  if (es_) {
    // replay: the same asks, told the stored fitness (no simulation)
    const int lam = es_->lambda;
    DIVCOLL_DEMAND(static_cast<int>(st.es_fitness.size()) >= done * lam);
    const bool keep = s_.keep_best;
    s_.keep_best = false;  // the best weights come from the state, not from replayed offers
    for (int it = 0; it < done; ++it) {
      ask(it);
      std::vector<ProbeResult> rs(lam);
      for (int i = 0; i < lam; ++i) {
        const double f = st.es_fitness[static_cast<size_t>(it) * lam + i];
        rs[i].ok = f != kBadFitness;
        rs[i].travel_u = -f;
      }
      tell(it, rs, kNaN);
    }
    s_.keep_best = keep;
    return;
  }
  params_ = st.params;
  adam_.m = st.m;
  adam_.v = st.v;
}

std::vector<std::pair<int, int>> validation_pairs(bool diverse, int n, int batch_pairs, int population, uint64_t seed,
                                                  uint64_t stream) {
  if (diverse) {
    Rng rng = make_rng(seed, stream, config::kItemValidationPairs);
    return collective::random_pairs(rng, population, n);
  }
  std::vector<std::pair<int, int>> p;
  for (int j = 0; j < n; ++j) {
    const int a = (batch_pairs + j) % population;
    p.emplace_back(a, a);
  }
  return p;
}

ProbeResult run_probe(sim::Simulator& sim, const std::vector<morph::Agent>& agents,
                      const std::vector<std::pair<int, int>>& pairs, const std::vector<double>& weights, bool grad,
                      const collective::Tether& tether, const sim::RunPhysics& physics, int steps, int bptt_window,
                      double pair_clip) {
  sim::RunOptions opt = physics.options();
  opt.steps = steps;
  opt.grad = grad;
  opt.agent_param_grad = false;  // the agents stay frozen
  opt.grad_window = bptt_window;
  ProbeSum sum;
  sum.pair_clip = pair_clip;
  for (const auto& [a, b] : pairs) sum.add(collective::run_pair(sim, agents[a], agents[b], weights, tether, "flat", physics.contact, opt, nullptr));
  return sum.mean();
}

PlainTrainResult train_plain(sim::Simulator& sim, const std::vector<morph::Agent>& agents, const OptSettings& s,
                             std::vector<double> init, const PlainTrainSpec& spec) {
  const int pop = static_cast<int>(agents.size());
  ConnectorOptimizer opt(s, std::move(init), spec.iterations, spec.seed, spec.stream);
  std::vector<std::pair<int, int>> val;
  if (spec.validation_pairs > 0)
    val = validation_pairs(spec.diverse, spec.validation_pairs, spec.batch_pairs, pop, spec.seed, spec.stream);
  PlainTrainResult out;
  auto validate = [&]() {
    if (val.empty()) return kNaN;
    out.pair_episodes_fwd += static_cast<long>(val.size());
    return run_probe(sim, agents, val, opt.current(), false, spec.tether, spec.physics, spec.episode_steps, 0).travel_bl;
  };
  for (int it = 0; it < spec.iterations; ++it) {
    std::vector<std::pair<int, int>> batch;
    if (spec.diverse) {
      Rng rng = make_rng(spec.seed, spec.stream, static_cast<uint64_t>(it));
      batch = collective::random_pairs(rng, pop, spec.batch_pairs);
    } else {
      batch = collective::uniform_pairs(spec.batch_pairs);
    }
    std::vector<ProbeResult> rs;
    for (const Probe& p : opt.ask(it)) {
      rs.push_back(run_probe(sim, agents, batch, p.weights, p.grad, spec.tether, spec.physics,
                             training_steps(s, spec.episode_steps, it), s.bptt_window, pair_clip(s)));
      (p.grad ? out.pair_episodes_grad : out.pair_episodes_fwd) += static_cast<long>(batch.size());
    }
    const double v = validate();
    out.val_bl.push_back(v);
    opt.tell(it, rs, v);
    out.curve_bl.push_back(opt.curve_bl);
  }
  const double v = validate();
  out.val_bl.push_back(v);
  opt.finish(v);
  out.params = opt.result();
  out.last_params = opt.current();
  out.best_iteration = opt.best_iteration();
  return out;
}

}  // namespace divcoll::evo
