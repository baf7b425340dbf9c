// connector optimisation options: the decaying rate follows its schedule, keep-best returns the
// validation-best weights, truncated backpropagation equals the full gradient when the window covers the
// episode and differs when it cuts (finite differences of the truncated objective would need the engine to
// start from a stored state, which it cannot), gradient averaging is exact on a quadratic, CMA-ES improves a known objective and resumes
// bit-identically from its stored fitness, whatever order the probes are evaluated in
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "evo/connector_opt.hpp"
#include "morph/body.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

using evo::ConnectorOptimizer;
using evo::OptSettings;
using evo::Probe;
using evo::ProbeResult;

// a known objective: travel(θ) = −|θ − c|², its gradient −2(θ − c)
ProbeResult quadratic(const std::vector<double>& w, bool grad) {
  ProbeResult r;
  r.ok = 1;
  double s = 0;
  for (size_t q = 0; q < w.size(); ++q) s += (w[q] - 0.3 * q) * (w[q] - 0.3 * q);
  r.travel_u = r.travel_bl = -s;
  if (grad)
    for (size_t q = 0; q < w.size(); ++q) r.grad.push_back(-2 * (w[q] - 0.3 * q));
  return r;
}
double distance_to_optimum(const std::vector<double>& w) { return std::sqrt(-quadratic(w, false).travel_u); }

std::vector<ProbeResult> evaluate(const std::vector<Probe>& probes) {
  std::vector<ProbeResult> rs;
  for (const Probe& p : probes) rs.push_back(quadratic(p.weights, p.grad));
  return rs;
}

// a pair whose episode ran but whose gradient overflowed is numerical trouble of that pair: it is left out of the
// mean and counted, so it cannot turn the weights into NaN (seen in float_networks at paper scale: 3 of 20 strong
// connectors, postprocess/RESULTS.md "The whole paper in float")
TEST(ConnectorOpt, APairWithANonFiniteGradientIsLeftOutAndCounted) {
  evo::ProbeSum sum;
  collective::PairOutcome good, overflowed, failed;
  good.travel_u = 0.5, good.travel_bl = 2.0, good.grad = {1.0, -2.0};
  overflowed.travel_u = 0.7, overflowed.travel_bl = 3.0, overflowed.grad = {INFINITY, 1.0};
  failed.status = sim::Status::nan, failed.travel_u = NAN;
  sum.add(good), sum.add(overflowed), sum.add(failed);
  const ProbeResult r = sum.mean();
  EXPECT_EQ(r.ok, 1);
  EXPECT_EQ(r.not_ok, 2);
  EXPECT_EQ(r.bad_grad, 1);
  EXPECT_EQ(r.travel_bl, 2.0);
  EXPECT_EQ(r.grad, (std::vector<double>{1.0, -2.0}));
  collective::PairOutcome nan_grad = good;
  nan_grad.grad[1] = NAN;
  evo::ProbeSum only_bad;
  only_bad.add(nan_grad);
  EXPECT_EQ(only_bad.mean().ok, 0);
  EXPECT_TRUE(std::isnan(only_bad.mean().travel_bl));
}

// a float pair whose gradient was redone in double (sim::RunResult::redone_in_double) is an ordinary ok pair
// in the mean, and counted so that the connectors plan can say so
TEST(ConnectorOpt, APairRedoneInDoubleCountsInTheMeanAndIsCounted) {
  collective::PairOutcome a, b;
  a.travel_u = 0.5, a.travel_bl = 2.0, a.grad = {1.0, -2.0};
  b.travel_u = 0.3, b.travel_bl = 1.0, b.grad = {3.0, 4.0}, b.redone_in_double = true;
  evo::ProbeSum sum;
  sum.add(a), sum.add(b);
  const ProbeResult r = sum.mean();
  EXPECT_EQ(r.ok, 2);
  EXPECT_EQ(r.not_ok, 0);
  EXPECT_EQ(r.redone, 1);
  EXPECT_EQ(r.travel_bl, 1.5);
  EXPECT_EQ(r.grad, (std::vector<double>{2.0, 1.0}));
}

// connectors.clip: a batch of four pairs whose gradients point along +x (norm 0.5) and one exploding pair along
// +y (norm 1000). Global clipping (the default) clips the batch mean, whose direction the exploding pair sets;
// per_pair clips each pair's gradient to clip_norm first, so the four others set the direction of the step
// (a normalized step, θ ← θ − lr·g/‖g‖, moves along the mean gradient; Adam's first step is lr·sign per weight)
TEST(ConnectorOpt, PerPairClippingKeepsAnExplodingPairFromSettingTheDirection) {
  std::vector<collective::PairOutcome> batch(5);
  for (int k = 0; k < 4; ++k) batch[k].travel_u = 0.1, batch[k].travel_bl = 0.5, batch[k].grad = {0.5, 0.0};
  batch[4].travel_u = 0.1, batch[4].travel_bl = 0.5, batch[4].grad = {0.0, 1000.0};
  auto step = [&](const std::string& clip) {
    OptSettings s = evo::opt_settings(config::default_config().connectors);
    s.clip = clip;
    s.clip_norm = 1.0;
    evo::ProbeSum sum;
    sum.pair_clip = evo::pair_clip(s);
    for (const auto& o : batch) sum.add(o);
    ProbeResult r = sum.mean();
    for (double& x : r.grad) x = -x;  // loss = −travel, as the connectors stage
    std::vector<double> p = {0.0, 0.0};
    evo::normalized_step(p, r.grad, 0.01);
    return std::pair{r.grad, p};
  };
  const auto [gg, pg] = step("global");
  const auto [gp, pp] = step("per_pair");
  // the mean loss gradients: global −(2, 1000)/5, per_pair −(2, 1)/5
  EXPECT_DOUBLE_EQ(gg[0], -0.4);
  EXPECT_DOUBLE_EQ(gg[1], -200.0);
  EXPECT_DOUBLE_EQ(gp[0], -0.4);
  EXPECT_DOUBLE_EQ(gp[1], -0.2);
  // the steps (both of length 0.01): global almost all along the exploding pair's y, per_pair mostly along x
  EXPECT_GT(pg[1], 100 * pg[0]);
  EXPECT_GT(pg[0], 0.0);
  EXPECT_DOUBLE_EQ(pp[0], 0.01 * 2 / std::sqrt(5.0));
  EXPECT_DOUBLE_EQ(pp[1], 0.01 * 1 / std::sqrt(5.0));
  // per_pair leaves pairs within clip_norm bit for bit as the default does
  evo::ProbeSum a, b;
  b.pair_clip = 1.0;
  for (int k = 0; k < 4; ++k) a.add(batch[k]), b.add(batch[k]);
  EXPECT_EQ(a.mean().grad, b.mean().grad);
  EXPECT_EQ(evo::pair_clip(evo::opt_settings(config::default_config().connectors)), 0.0);  // the default: no per-pair clipping
}

TEST(ConnectorOpt, DecayingRateFollowsItsSchedule) {
  OptSettings s = evo::opt_settings(config::default_config().connectors);
  s.lr = 0.01;
  s.lr_final = 0.1;
  EXPECT_EQ(evo::scheduled_lr(s, 0, 50), 0.01);
  EXPECT_EQ(evo::scheduled_lr(s, 49, 50), 0.01);  // constant
  s.lr_schedule = "cosine";
  EXPECT_DOUBLE_EQ(evo::scheduled_lr(s, 0, 51), 0.01);
  EXPECT_DOUBLE_EQ(evo::scheduled_lr(s, 25, 51), 0.01 * (0.1 + 0.9 * 0.5));
  EXPECT_DOUBLE_EQ(evo::scheduled_lr(s, 50, 51), 0.001);
  for (int it = 1; it < 51; ++it) EXPECT_LT(evo::scheduled_lr(s, it, 51), evo::scheduled_lr(s, it - 1, 51));
  s.lr_schedule = "exponential";
  EXPECT_DOUBLE_EQ(evo::scheduled_lr(s, 0, 11), 0.01);
  EXPECT_DOUBLE_EQ(evo::scheduled_lr(s, 10, 11), 0.001);
  for (int it = 1; it < 11; ++it)  // geometric: the same ratio every iteration
    EXPECT_NEAR(evo::scheduled_lr(s, it, 11) / evo::scheduled_lr(s, it - 1, 11), std::pow(0.1, 0.1), 1e-12);
  // and the optimizer uses it: normalized steps of length lr_t
  s.optimizer = "normalized";
  ConnectorOptimizer opt(s, std::vector<double>(4, 5.0), 11, 1, 1);
  for (int it = 0; it < 11; ++it) {
    const std::vector<double> before = opt.current();
    opt.tell(it, evaluate(opt.ask(it)), NAN);
    double d = 0;
    for (size_t q = 0; q < before.size(); ++q) d += (opt.current()[q] - before[q]) * (opt.current()[q] - before[q]);
    EXPECT_NEAR(std::sqrt(d), evo::scheduled_lr(s, it, 11), 1e-12);
  }
}

TEST(ConnectorOpt, TheHorizonCurriculumGrowsTheTrainingEpisodeToItsFullLength) {
  OptSettings s = evo::opt_settings(config::default_config().connectors);
  for (int it : {0, 7, 99}) EXPECT_EQ(evo::training_steps(s, 1000, it), 1000);  // the default: no curriculum
  EXPECT_FALSE(evo::extended(s));
  s.horizon_start = 100;
  s.horizon_ramp = 50;
  EXPECT_TRUE(evo::extended(s));
  EXPECT_EQ(evo::training_steps(s, 1000, 0), 100);
  EXPECT_EQ(evo::training_steps(s, 1000, 1), 118);  // 100 + 900·1/50
  EXPECT_EQ(evo::training_steps(s, 1000, 25), 550);
  EXPECT_EQ(evo::training_steps(s, 1000, 49), 982);
  for (int it : {50, 51, 99}) EXPECT_EQ(evo::training_steps(s, 1000, it), 1000);
  int last = 0;
  for (int it = 0; it < 60; ++it) {  // never shrinks
    EXPECT_GE(evo::training_steps(s, 1000, it), last);
    last = evo::training_steps(s, 1000, it);
  }
  s.horizon_ramp = 0;  // a short horizon throughout
  for (int it : {0, 50, 99}) EXPECT_EQ(evo::training_steps(s, 1000, it), 100);
}

TEST(ConnectorOpt, KeepBestReturnsTheValidationBestWeights) {
  OptSettings s = evo::opt_settings(config::default_config().connectors);
  s.keep_best = true;
  s.lr = 0.05;
  const int I = 12;
  ConnectorOptimizer opt(s, std::vector<double>(5, 1.0), I, 1, 1);
  // a validation score that peaks at iteration 7 and falls after
  const double val[I + 1] = {0.1, 0.2, 0.3, 0.5, 0.6, 0.65, 0.7, 0.9, 0.4, 0.3, 0.2, 0.1, 0.05};
  std::vector<std::vector<double>> seen;
  for (int it = 0; it < I; ++it) {
    seen.push_back(opt.current());
    opt.tell(it, evaluate(opt.ask(it)), val[it]);
  }
  opt.finish(val[I]);
  EXPECT_EQ(opt.best_iteration(), 7);
  EXPECT_EQ(opt.best_score(), 0.9);
  EXPECT_EQ(opt.result(), seen[7]);
  EXPECT_NE(opt.result(), opt.current());
  // without keep_best the last weights
  s.keep_best = false;
  ConnectorOptimizer plain(s, std::vector<double>(5, 1.0), I, 1, 1);
  for (int it = 0; it < I; ++it) plain.tell(it, evaluate(plain.ask(it)), val[it]);
  EXPECT_EQ(plain.result(), plain.current());
  EXPECT_EQ(plain.current(), opt.current());  // keep-best does not change the trajectory
}

TEST(ConnectorOpt, GradientAveragingIsAntitheticAndExactOnAQuadratic) {
  OptSettings s = evo::opt_settings(config::default_config().connectors);
  s.grad_samples = 4;
  s.grad_sigma = 0.05;
  std::vector<double> init = {0.5, -0.2, 0.1, 0.9, 0.0, 0.3};
  ConnectorOptimizer avg(s, init, 10, 3, 7);
  const auto probes = avg.ask(0);
  ASSERT_EQ(probes.size(), 4u);
  for (int j = 0; j < 2; ++j)
    for (size_t q = 0; q < init.size(); ++q) {
      EXPECT_NEAR(0.5 * (probes[2 * j].weights[q] + probes[2 * j + 1].weights[q]), init[q], 1e-15);
      EXPECT_NE(probes[2 * j].weights[q], init[q]);
    }
  // the mean gradient of ± pairs of a quadratic is its gradient at θ: the same Adam trajectory as one sample
  s.grad_samples = 1;
  ConnectorOptimizer one(s, init, 10, 3, 7);
  for (int it = 0; it < 10; ++it) {
    avg.tell(it, evaluate(avg.ask(it)), NAN);
    one.tell(it, evaluate(one.ask(it)), NAN);
    for (size_t q = 0; q < init.size(); ++q) EXPECT_NEAR(avg.current()[q], one.current()[q], 1e-12);
  }
  // odd counts add the unperturbed weights
  s.grad_samples = 3;
  ConnectorOptimizer odd(s, init, 10, 3, 7);
  EXPECT_EQ(odd.ask(0).back().weights, init);
}

TEST(ConnectorOpt, CmaesImprovesAKnownObjectiveAndResumesFromItsFitness) {
  OptSettings s = evo::opt_settings(config::default_config().connectors);
  s.optimizer = "cmaes";
  s.es_popsize = 12;
  s.es_sigma = 0.1;
  const std::vector<double> init(10, 0.0);
  const int I = 60;
  ConnectorOptimizer es(s, init, I, 5, 9);
  const double d0 = distance_to_optimum(init);
  std::vector<double> at20;
  ConnectorOptimizer::State st20;
  for (int it = 0; it < I; ++it) {
    auto probes = es.ask(it);
    ASSERT_EQ(probes.size(), 12u);
    // evaluated in reverse order (as another rank count would), placed by index
    std::vector<ProbeResult> rs(probes.size());
    for (size_t i = probes.size(); i-- > 0;) rs[i] = quadratic(probes[i].weights, false);
    es.tell(it, rs, NAN);
    if (it == 19) st20 = es.state(), at20 = es.current();
  }
  EXPECT_LT(distance_to_optimum(es.current()), 0.2 * d0) << "CMA-ES did not approach the optimum";
  // a fresh optimizer restored after 20 iterations continues exactly as the uninterrupted one
  ConnectorOptimizer resumed(s, init, I, 5, 9);
  resumed.restore(st20, 20);
  EXPECT_EQ(resumed.current(), at20);
  for (int it = 20; it < I; ++it) resumed.tell(it, evaluate(resumed.ask(it)), NAN);
  EXPECT_EQ(resumed.current(), es.current());
  // another seed, another path
  ConnectorOptimizer other(s, init, I, 6, 9);
  other.tell(0, evaluate(other.ask(0)), NAN);
  ConnectorOptimizer same(s, init, I, 5, 9);
  same.tell(0, evaluate(same.ask(0)), NAN);
  EXPECT_NE(other.current(), same.current());
}

TEST(ConnectorOpt, AntitheticEsImprovesAKnownObjectiveAndResumesFromItsState) {
  OptSettings s = evo::opt_settings(config::default_config().connectors);
  s.optimizer = "es";
  s.es_popsize = 10;
  s.es_sigma = 0.05;
  s.lr = 0.05;
  s.clip_norm = 1e6;
  const std::vector<double> init(10, 0.0);
  const int I = 150;
  ConnectorOptimizer es(s, init, I, 5, 9);
  ConnectorOptimizer::State st;
  std::vector<double> at50;
  for (int it = 0; it < I; ++it) {
    const auto probes = es.ask(it);
    ASSERT_EQ(probes.size(), 10u);
    for (const Probe& p : probes) EXPECT_FALSE(p.grad);
    // antithetic pairs around the current weights
    for (size_t q = 0; q < init.size(); ++q)
      EXPECT_NEAR(0.5 * (probes[0].weights[q] + probes[1].weights[q]), es.current()[q], 1e-12);
    std::vector<ProbeResult> rs(probes.size());
    for (size_t i = probes.size(); i-- > 0;) rs[i] = quadratic(probes[i].weights, false);  // any order
    es.tell(it, rs, NAN);
    if (it == 49) st = es.state(), at50 = es.current();
  }
  EXPECT_LT(distance_to_optimum(es.current()), 0.2 * distance_to_optimum(init));
  ConnectorOptimizer resumed(s, init, I, 5, 9);
  resumed.restore(st, 50);
  EXPECT_EQ(resumed.current(), at50);
  for (int it = 50; it < I; ++it) resumed.tell(it, evaluate(resumed.ask(it)), NAN);
  EXPECT_EQ(resumed.current(), es.current());
}

TEST(ConnectorOpt, TruncatedBackpropagationEqualsTheFullGradientWhenTheWindowCoversTheEpisode) {
  const morph::Agent p = testing::agent_with_anchors(1, 77), q = testing::agent_with_anchors(2, 77);
  Rng wrng = make_rng(4, 1, 0);
  const std::vector<double> w = morph::init_connector_params(wrng, 1.0);
  sim::Simulator sim;
  sim::RunOptions opt;
  opt.steps = 120;
  opt.grad = true;
  const auto full = collective::run_pair(sim, p, q, w, testing::weak_connector(), "flat", testing::kCoulomb, opt, nullptr);
  for (int W : {120, 500}) {
    opt.grad_window = W;
    const auto tr = collective::run_pair(sim, p, q, w, testing::weak_connector(), "flat", testing::kCoulomb, opt, nullptr);
    EXPECT_EQ(tr.grad, full.grad) << "window " << W;
    EXPECT_EQ(tr.travel_u, full.travel_u);
  }
  // a shorter window cuts the adjoint
  opt.grad_window = 60;
  const auto cut = collective::run_pair(sim, p, q, w, testing::weak_connector(), "flat", testing::kCoulomb, opt, nullptr);
  EXPECT_NE(cut.grad, full.grad);
  sim::RunOptions o60;
  o60.steps = 60;
  o60.grad = true;
  const auto g60 = collective::run_pair(sim, p, q, w, testing::weak_connector(), "flat", testing::kCoulomb, o60, nullptr);
  o60.grad_window = 60;  // a window as long as the episode: no cut
  EXPECT_EQ(collective::run_pair(sim, p, q, w, testing::weak_connector(), "flat", testing::kCoulomb, o60, nullptr).grad, g60.grad);
  o60.grad_window = 30;  // cut inside: differs from the 60-step full gradient
  EXPECT_NE(collective::run_pair(sim, p, q, w, testing::weak_connector(), "flat", testing::kCoulomb, o60, nullptr).grad, g60.grad);
  // truncation changes only the gradient, never the episode
  EXPECT_EQ(cut.travel_u, full.travel_u);
}

}  // namespace
}  // namespace divcoll
