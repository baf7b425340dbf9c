// RunOptions::float_networks: the controllers' networks in float, the physics in double. Not the spec's step
// (SPEC §10 is double), so it is checked against the double engine and against its own finite differences:
// it follows double over a short episode, its reverse-mode gradient is the gradient of its own travel, and it
// is as deterministic as double (taped and untaped runs, repeated runs: the same bits)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "collective/builders.hpp"
#include "collective/pairs.hpp"
#include "config/environments.hpp"
#include "io/scene_file.hpp"
#include "sim/engine.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

constexpr int kSteps = 150;

using testing::dot;

// directions from stream 3
std::vector<double> direction(size_t n, uint64_t seed) { return testing::unit_direction(n, seed, 3); }

sim::Scene pair_in(const std::string& env) {
  const testing::GradientPair& f = testing::gradient_pair();
  return collective::pair_scene(f.p, f.a, f.conn, testing::weak_connector(), env, testing::kCoulomb);
}

sim::RunResult run(const sim::Scene& s, bool grad, bool fl, int steps = kSteps) {
  sim::RunOptions opt;
  opt.steps = steps;
  opt.grad = grad;
  opt.float_networks = fl;
  return sim::simulate(s, opt);
}

class FloatNetworks : public ::testing::TestWithParam<std::string> {};

// float follows double: travel within 1e-7 u after 150 steps, and every gradient block's directional
// derivative within 0.1% of double's (measured: 8e-10 u, and 1e-5 relative at most)
TEST_P(FloatNetworks, FollowsDoubleOverAShortEpisode) {
  const sim::Scene s = pair_in(GetParam());
  const sim::RunResult d = run(s, true, false), f = run(s, true, true);
  ASSERT_EQ(d.status, sim::Status::ok) << d.message;
  ASSERT_EQ(f.status, sim::Status::ok) << f.message;
  EXPECT_NE(d.travel, f.travel) << "the float networks were not used";
  EXPECT_NEAR(f.travel, d.travel, 1e-7);
  const std::pair<const char*, std::pair<const std::vector<double>*, const std::vector<double>*>> blocks[] = {
      {"agent_params", {&d.grad_agent_params, &f.grad_agent_params}},
      {"connector_params", {&d.grad_connector_params, &f.grad_connector_params}},
      {"x0", {&d.grad_x0, &f.grad_x0}},
      {"rest_length", {&d.grad_rest_length, &f.grad_rest_length}}};
  for (const auto& [name, g] : blocks) {
    ASSERT_EQ(g.first->size(), g.second->size()) << name;
    const std::vector<double> dir = direction(g.first->size(), 7);
    const double a = dot(*g.first, dir), b = dot(*g.second, dir);
    EXPECT_NEAR(b, a, 1e-3 * std::max(std::abs(a), 1e-4)) << GetParam() << " " << name;
  }
}

// the float gradient is the gradient of the float travel: central differences of the float engine itself
// (step 1e-4: float's rounding of the networks makes travel rough below that), to 2%
TEST_P(FloatNetworks, GradientMatchesItsOwnCentralDifferences) {
  const sim::Scene s = pair_in(GetParam());
  const sim::RunResult r = run(s, true, true);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  const double eps = 1e-4;
  auto check = [&](const char* name, const std::vector<double>& grad, auto apply) {
    const std::vector<double> dir = direction(grad.size(), 9);
    sim::Scene plus = s, minus = s;
    apply(plus, dir, eps);
    apply(minus, dir, -eps);
    const double num = (run(plus, false, true).travel - run(minus, false, true).travel) / (2 * eps);
    const double ana = dot(grad, dir);
    EXPECT_NEAR(ana, num, 2e-2 * std::max({std::abs(ana), std::abs(num), 1e-3})) << GetParam() << " " << name;
  };
  auto add = [](std::vector<double>& v, const std::vector<double>& d, double e) {
    for (size_t i = 0; i < v.size(); ++i) v[i] += e * d[i];
  };
  check("connector_params", r.grad_connector_params,
        [&](sim::Scene& sc, const std::vector<double>& d, double e) { add(sc.connector_params, d, e); });
  check("agent_params", r.grad_agent_params,
        [&](sim::Scene& sc, const std::vector<double>& d, double e) { add(sc.agent_params, d, e); });
}

INSTANTIATE_TEST_SUITE_P(SomeEnvironments, FloatNetworks, ::testing::Values("flat", "step_up", "treadmill"),
                         [](const auto& info) { return info.param; });

// deterministic as double is: taped and untaped runs, and a second run on a reused simulator, give the same bits
TEST(FloatNetworksDeterminism, TapedUntapedAndRepeatedRunsGiveTheSameBits) {
  const sim::Scene s = pair_in("flat");
  sim::Simulator sim;
  sim::RunOptions opt;
  opt.steps = 400;
  opt.float_networks = true;
  opt.record = true;
  const sim::RunResult a = sim.run(s, opt);
  opt.grad = true;
  const sim::RunResult b = sim.run(s, opt);
  const sim::RunResult c = sim.run(s, opt);
  ASSERT_EQ(a.x.size(), b.x.size());
  EXPECT_EQ(std::memcmp(a.x.data(), b.x.data(), sizeof(double) * a.x.size()), 0);
  EXPECT_EQ(std::memcmp(b.x.data(), c.x.data(), sizeof(double) * b.x.size()), 0);
  EXPECT_EQ(std::memcmp(b.grad_connector_params.data(), c.grad_connector_params.data(),
                        sizeof(double) * b.grad_connector_params.size()),
            0);
  EXPECT_FALSE(b.redone_in_double) << "an ordinary pair's float gradient is finite";
}

// the precision is the caller's to give (sim::RunPhysics, from run.precision): RunPhysics::options() and the
// collective runners given it run the networks in float, bit for bit as RunOptions::float_networks does, and
// episodes of both precisions alternate on one simulator (nothing process-wide: RunOptions defaults to double)
TEST(FloatNetworksDeterminism, ThePrecisionGivenReachesTheEngine) {
  EXPECT_FALSE(sim::RunOptions{}.float_networks);
  const sim::RunPhysics fl{sim::ContactLaw::coulomb, true};
  EXPECT_TRUE(fl.options().float_networks);
  EXPECT_FALSE(testing::kSpec.options().float_networks);
  const testing::GradientPair& f = testing::gradient_pair();
  const sim::Scene s = pair_in("flat");
  sim::RunOptions opt;
  opt.steps = 200;
  opt.grad = true;
  opt.agent_param_grad = false;
  const sim::RunResult d = sim::simulate(s, opt);
  opt.float_networks = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok);
  ASSERT_NE(r.travel, d.travel) << "float and double agree to the bit: the test cannot tell them apart";
  sim::Simulator sim;
  for (int round = 0; round < 2; ++round) {
    const collective::PairOutcome pf = collective::run_pair(sim, f.p, f.a, f.conn, testing::weak_connector(), "flat",
                                                            fl, 200, true);
    const collective::PairOutcome pd = collective::run_pair(sim, f.p, f.a, f.conn, testing::weak_connector(), "flat",
                                                            testing::kSpec, 200, true);
    EXPECT_EQ(pf.travel_u, r.travel);
    EXPECT_EQ(pf.grad, r.grad_connector_params);
    EXPECT_EQ(pd.travel_u, d.travel);
    EXPECT_EQ(pd.grad, d.grad_connector_params);
  }
  // an agent alone and its training: float given, float run
  sim::RunOptions fwd = fl.options();
  fwd.steps = 200;
  const double alone_f = sim::simulate(collective::agent_scene(f.p, "flat", sim::ContactLaw::coulomb), fwd).travel;
  EXPECT_EQ(collective::run_alone(sim, f.p, "flat", fl, 200).travel_u, alone_f);
  EXPECT_NE(collective::run_alone(sim, f.p, "flat", testing::kSpec, 200).travel_u, alone_f);
}

// float's range ends at 3.4e38. The scene: the float paper run's connectors stage rerun (postprocess/RESULTS.md, 3b8fa66),
// strong uniform-trained replicate 7's final connector joining agent 2 of the final population to its clone,
// on flat: over 1000 steps (a training episode) its gradient reaches 7e43 in double, and the float pass
// overflowed. Such an episode is redone with the networks in double: the caller gets double's finite result.
TEST(FloatNetworksRange, AnEpisodeWhoseFloatGradientOverflowsIsRedoneInDouble) {
  const sim::Scene s = io::read_scene(std::string(DIVCOLL_SOURCE_DIR) + "/tests/sim/data/float_overflow_pair.h5");
  sim::Simulator sim;
  sim::RunOptions opt;
  opt.steps = 1000;
  opt.grad = true;
  opt.agent_param_grad = false;  // as connector training asks
  opt.float_networks = true;
  const sim::RunResult f = sim.run(s, opt);
  opt.float_networks = false;
  const sim::RunResult d = sim.run(s, opt);
  ASSERT_EQ(d.status, sim::Status::ok);
  double largest = 0;
  for (double g : d.grad_connector_params) largest = std::max(largest, std::abs(g));
  ASSERT_TRUE(std::isfinite(largest));
  EXPECT_GT(largest, std::numeric_limits<float>::max()) << "the scene no longer needs more than float's range";
  EXPECT_TRUE(f.redone_in_double);
  EXPECT_FALSE(d.redone_in_double);
  ASSERT_EQ(f.status, sim::Status::ok);
  EXPECT_EQ(std::memcmp(&f.travel, &d.travel, sizeof(double)), 0);
  ASSERT_EQ(f.grad_connector_params.size(), d.grad_connector_params.size());
  EXPECT_EQ(std::memcmp(f.grad_connector_params.data(), d.grad_connector_params.data(),
                        sizeof(double) * d.grad_connector_params.size()),
            0);
  EXPECT_EQ(f.grad_x0, d.grad_x0);
}

}  // namespace
}  // namespace divcoll
