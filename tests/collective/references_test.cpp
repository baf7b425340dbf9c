// the reference connectors (collective/references.hpp): the follower policy's weights and what they do to a pair's
// springs, the three references' tethers, and the training start they give (connectors.init)
#include "collective/references.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "common/check.hpp"
#include "config/config.hpp"
#include "morph/body.hpp"
#include "nn/mlp.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

// the network's output (post-tanh) for one input column
double net_out(const std::vector<double>& w, const std::vector<double>& input) {
  const nn::Layout L = nn::connector_layout();
  std::vector<double> acts(L.activation_count(), 0.0);
  std::copy(input.begin(), input.end(), acts.begin());
  nn::forward(L, w.data(), 1, acts.data());
  return acts[L.activation_offset(L.n_layers())];
}

TEST(FollowerPolicy, FourNonZeroWeightsThatReadOnlyTheSpringsLengthRatio) {
  const std::vector<double> w = collective::follower_connector_params(0.6);
  ASSERT_EQ(static_cast<int>(w.size()), sim::connector_param_count());
  int nonzero = 0;
  for (double x : w) nonzero += x != 0.0;
  EXPECT_EQ(nonzero, 4);
  // at rest length the target is the rest length (output 0), whatever the other ten inputs say
  std::vector<double> in = {0.3, -0.2, 0.1, 0.4, 1.5, -2.0, 0.7, 0.1, 1.0, 0.0, 1.0};
  EXPECT_EQ(net_out(w, in), 0.0);
  // stretched or compressed by a few per cent: out ≈ (ℓ/L − 1)/a, so that L·(1 + a·out) ≈ ℓ
  for (double ratio : {0.9, 0.97, 1.03, 1.1}) {
    in[10] = ratio;
    const double target = (ratio - 1.0) / 0.6;
    EXPECT_NEAR(net_out(w, in), target, 0.02 * std::abs(target) + 1e-3) << ratio;
    in[0] = -in[0];  // the other inputs do not matter
    EXPECT_NEAR(net_out(w, in), target, 0.02 * std::abs(target) + 1e-3) << ratio;
  }
  EXPECT_THROW(collective::follower_connector_params(0.0), InputError);
}

// the joint network (connectors.network = joint) carries the same policy in 20 non-zero weights, and a pair under it
// moves exactly as under the per-spring follower: the joint network computes what the per-spring one does, column
// for column, when its weights say so
TEST(FollowerPolicy, TheJointNetworksFollowerMovesAPairBitForBitAsThePerSpringOne) {
  const std::vector<double> w = collective::follower_connector_params(0.6, /*joint=*/true);
  ASSERT_EQ(static_cast<int>(w.size()), sim::connector_param_count(true));
  int nonzero = 0;
  for (double x : w) nonzero += x != 0.0;
  EXPECT_EQ(nonzero, 20);
  const config::RunConfig cfg = config::default_config();
  const collective::Tether t = collective::tether(cfg.connectors, "weak_uniform");
  for (uint64_t seed : {1, 2}) {
    const morph::Agent a = testing::agent_with_anchors(seed, 77), b = testing::agent_with_anchors(seed + 10, 77);
    sim::RunOptions opt;
    opt.steps = 400;
    opt.record = true;
    const sim::RunResult per_spring = sim::simulate(
        collective::pair_scene(a, b, collective::follower_connector_params(0.6), t, "flat", testing::kCoulomb), opt);
    const sim::RunResult joint = sim::simulate(collective::pair_scene(a, b, w, t, "flat", testing::kCoulomb), opt);
    ASSERT_EQ(per_spring.status, sim::Status::ok);
    EXPECT_EQ(joint.x, per_spring.x) << "seed " << seed;
    EXPECT_EQ(joint.travel, per_spring.travel) << "seed " << seed;
  }
}

// the mean over steps and connector springs of |ℓ/L − (1 + a·o)|, the stretch the spring's elastic force acts on
// (force k·L·that), for a clone pair under connector weights w: o replayed from the recorded network inputs with the
// controller's smoothing o ← α·out + (1 − α)·o (SPEC §2 step 1; α of SPEC §6.3)
double mean_elastic_stretch(const morph::Agent& a, const std::vector<double>& w, const collective::Tether& t, int T) {
  const sim::Scene scene = collective::pair_scene(a, a, w, t, "flat", testing::kCoulomb);
  sim::RunOptions opt;
  opt.steps = T;
  opt.record_hidden = true;
  opt.record_inputs = true;
  opt.hidden_every = 1;
  const sim::RunResult r = sim::simulate(scene, opt);
  EXPECT_EQ(r.status, sim::Status::ok);
  const int I = sim::kConnectorInputs, S = sim::kConnectorSprings;
  EXPECT_EQ(r.inputs.size(), static_cast<size_t>(T) * S * I);
  const double alpha = sim::Constants{}.conn_alpha;
  std::vector<double> o(S, 0.0);
  double sum = 0;
  for (int step = 0; step < T; ++step)
    for (int s = 0; s < S; ++s) {
      const std::vector<double> in(r.inputs.begin() + (static_cast<size_t>(step) * S + s) * I,
                                   r.inputs.begin() + (static_cast<size_t>(step) * S + s + 1) * I);
      o[s] = alpha * net_out(w, in) + (1 - alpha) * o[s];
      sum += std::abs(in[10] - (1.0 + t.amplitude * o[s]));
    }
  return sum / (static_cast<double>(T) * S);
}

TEST(FollowerPolicy, KeepsTheSpringForcesOfACloneClonePairSmall) {
  const config::RunConfig cfg = config::default_config();
  const collective::ReferenceConnector passive = collective::reference_connector(cfg.connectors, "passive");
  const collective::ReferenceConnector follower = collective::reference_connector(cfg.connectors, "follower");
  for (uint64_t seed : {1, 2, 3}) {
    const morph::Agent a = testing::agent_with_anchors(seed, 77);
    const double held = mean_elastic_stretch(a, passive.weights, passive.tether, 600);
    const double followed = mean_elastic_stretch(a, follower.weights, follower.tether, 600);
    EXPECT_GT(held, 1e-3) << "seed " << seed << ": the passive tether is barely stretched; the comparison says little";
    EXPECT_LT(followed, 0.5 * held) << "seed " << seed << ": passive " << held << ", follower " << followed;
  }
}

TEST(ReferenceConnectors, FreeHasNoSpringForcePassiveAndFollowerAreWeak) {
  const config::RunConfig cfg = config::apply_overrides(config::default_config(), {"connectors.damping=2.0"});
  const collective::Tether weak = collective::tether(cfg.connectors, "weak_uniform");
  const auto free = collective::reference_connector(cfg.connectors, "free");
  EXPECT_EQ(free.tether.stiffness, 0.0);
  EXPECT_EQ(free.tether.damping, 0.0);
  for (const char* name : {"passive", "follower"}) {
    const auto r = collective::reference_connector(cfg.connectors, name);
    EXPECT_EQ(r.tether.stiffness, weak.stiffness) << name;
    EXPECT_EQ(r.tether.amplitude, weak.amplitude) << name;
    EXPECT_EQ(r.tether.damping, 2.0) << name;
  }
  for (double x : collective::reference_connector(cfg.connectors, "passive").weights) EXPECT_EQ(x, 0.0);
  EXPECT_EQ(collective::reference_connector(cfg.connectors, "follower").weights,
            collective::follower_connector_params(cfg.connectors.amplitude));
  EXPECT_THROW(collective::reference_connector(cfg.connectors, "loose"), InputError);
}

TEST(ConnectorInit, RandomIsTheSpecsInitAndFollowerIsThePolicyPlusNoise) {
  config::RunConfig cfg = config::default_config();
  Rng a = make_rng(4, 2000, 1000000), b = make_rng(4, 2000, 1000000);
  EXPECT_EQ(collective::initial_connector_params(cfg.connectors, 0.6, a),
            morph::init_connector_params(b, cfg.connectors.init_out_gain));
  cfg = config::apply_overrides(cfg, {"connectors.init=\"follower\"", "connectors.init_noise=0"});
  Rng c = make_rng(4, 2000, 1000000);
  EXPECT_EQ(collective::initial_connector_params(cfg.connectors, 0.6, c), collective::follower_connector_params(0.6));
  cfg = config::apply_overrides(cfg, {"connectors.init_noise=0.01"});
  Rng d = make_rng(4, 2000, 1000000);
  const std::vector<double> w = collective::initial_connector_params(cfg.connectors, 0.6, d);
  const std::vector<double> f = collective::follower_connector_params(0.6);
  double sq = 0;
  for (size_t i = 0; i < w.size(); ++i) sq += (w[i] - f[i]) * (w[i] - f[i]);
  EXPECT_NEAR(std::sqrt(sq / w.size()), 0.01, 0.001);  // 1473 draws of N(0, 0.01²)
  // connectors.network = joint: the same starts in the joint network's layout
  cfg = config::apply_overrides(cfg, {"connectors.network=\"joint\"", "connectors.init_noise=0",
                                      "run.stages=agents,connectors,deploy"});
  Rng e = make_rng(4, 2000, 1000000);
  EXPECT_EQ(collective::initial_connector_params(cfg.connectors, 0.6, e), collective::follower_connector_params(0.6, true));
  cfg = config::apply_overrides(cfg, {"connectors.init=\"random\""});
  Rng g = make_rng(4, 2000, 1000000), h = make_rng(4, 2000, 1000000);
  const std::vector<double> j = collective::initial_connector_params(cfg.connectors, 0.6, g);
  EXPECT_EQ(static_cast<int>(j.size()), sim::connector_param_count(true));
  EXPECT_EQ(j, morph::init_connector_params(h, cfg.connectors.init_out_gain, true));
}

}  // namespace
}  // namespace divcoll
