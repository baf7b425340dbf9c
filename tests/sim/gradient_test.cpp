// reverse-mode gradients against central finite differences, in every environment, for all four
// gradient blocks (agent params, connector params, x0, rest lengths), on scenes where floor and wall
// contact, the friction projection and the belt are active (counted, and asserted); the same under the
// no_slip contact law with kappa_ns = 0 and > 0
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "collective/builders.hpp"
#include "common/rng.hpp"
#include "config/environments.hpp"
#include "morph/body.hpp"
#include "sim/engine.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

constexpr int kSteps = 150;

using testing::dot;

// directions from stream 2
std::vector<double> direction(size_t n, uint64_t seed) { return testing::unit_direction(n, seed, 2); }

// a pair in `env`; terrain features start 0.05 − back u (0.003 unless said) ahead of the front, so that walls are
// hit early
sim::Scene pair_in(const std::string& env, double back = 0.047) {
  const testing::GradientPair& f = testing::gradient_pair();
  sim::Scene s = collective::pair_scene(f.p, f.a, f.conn, testing::weak_connector(), env, testing::kCoulomb);
  double mx = -1e9;
  for (int i = 0; i < s.n_masses(); ++i) mx = std::max(mx, s.x0[2 * i]);
  s.env = config::place_environment(config::environment_table(env), mx - back, testing::kCoulomb);
  return s;
}

double travel(const sim::Scene& s) {
  sim::RunOptions opt;
  opt.steps = kSteps;
  const sim::RunResult r = sim::simulate(s, opt);
  EXPECT_EQ(r.status, sim::Status::ok) << r.message;
  return r.travel;
}

using Apply = std::function<void(sim::Scene&, const std::vector<double>&, double)>;

// directional derivatives along d applied through `apply(scene, d, eps)`: central, forward, backward
struct Differences {
  double central, forward, backward;
};
Differences fd(const sim::Scene& s, const std::vector<double>& d, double eps, const Apply& apply) {
  sim::Scene plus = s, minus = s;
  apply(plus, d, eps);
  apply(minus, d, -eps);
  const double f0 = travel(s), fp = travel(plus), fm = travel(minus);
  return {(fp - fm) / (2 * eps), (fp - f0) / eps, (f0 - fm) / eps};
}

// travel is piecewise smooth: a perturbation can move a mass across the adhesion band or a contact
// branch, a jump that no derivative describes. Central differences must agree to 1e-4; where a jump
// falls inside [−ε, ε] it falls on one side only, and the one-sided difference on the other side must
// agree to 1e-3 (its truncation error is O(ε))
::testing::AssertionResult agrees(double analytic, const Differences& n) {
  auto rel = [&](double v) { return std::abs(analytic - v) / std::max({std::abs(analytic), std::abs(v), 1e-6}); };
  if (rel(n.central) < 1e-4 || rel(n.forward) < 1e-3 || rel(n.backward) < 1e-3) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "reverse mode " << analytic << ", central " << n.central << ", forward "
                                       << n.forward << ", backward " << n.backward;
}

class Gradient : public ::testing::TestWithParam<std::string> {};

// the four gradient blocks of an episode of `s` (agent params, connector params, x0, rest lengths) against
// central differences along a random direction each; with nonzero, each directional derivative must not be 0
void check_blocks(const sim::Scene& s, const sim::RunResult& r, const std::string& label, bool nonzero = false) {
  struct Block {
    const char* name;
    const std::vector<double>& grad;
    Apply apply;
    std::vector<double> mask;  // 1 where the direction may be nonzero
  };
  auto add = [](std::vector<double>& v, const std::vector<double>& d, double e) {
    for (size_t i = 0; i < v.size(); ++i) v[i] += e * d[i];
  };
  // x0: masses resting exactly on the ground sit on the kink of the time-of-impact clamp (φ = 0), where
  // the gradient is one-sided by definition; their y is left out of the direction (see DropTest below)
  std::vector<double> x0_mask(s.x0.size(), 1.0);
  for (int i = 0; i < s.n_masses(); ++i)
    if (s.x0[2 * i + 1] == 0.0) x0_mask[2 * i + 1] = 0.0;
  const std::vector<Block> blocks = {
      {"agent_params", r.grad_agent_params, [&](sim::Scene& sc, auto& d, double e) { add(sc.agent_params, d, e); },
       std::vector<double>(s.agent_params.size(), 1.0)},
      {"connector_params", r.grad_connector_params,
       [&](sim::Scene& sc, auto& d, double e) { add(sc.connector_params, d, e); },
       std::vector<double>(s.connector_params.size(), 1.0)},
      {"x0", r.grad_x0, [&](sim::Scene& sc, auto& d, double e) { add(sc.x0, d, e); }, x0_mask},
      {"rest_length", r.grad_rest_length, [&](sim::Scene& sc, auto& d, double e) { add(sc.rest_length, d, e); },
       std::vector<double>(s.rest_length.size(), 1.0)},
  };
  for (const Block& b : blocks) {
    std::vector<double> d = direction(b.grad.size(), 5);
    for (size_t i = 0; i < d.size(); ++i) d[i] *= b.mask[i];
    const double analytic = dot(b.grad, d);
    if (nonzero) {
      EXPECT_NE(analytic, 0.0) << label << " " << b.name;
    }
    EXPECT_TRUE(agrees(analytic, fd(s, d, 1e-7, b.apply))) << label << " " << b.name;
  }
}


TEST_P(Gradient, AllFourBlocksMatchCentralDifferences) {
  const sim::Scene s = pair_in(GetParam());
  sim::RunOptions opt;
  opt.steps = kSteps;
  opt.grad = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;

  // the features under test are exercised
  EXPECT_GT(r.contacts.floor, 0);
  EXPECT_GT(r.contacts.sliding, 0) << "friction projection never active";
  EXPECT_GT(r.contacts.toi, 0);
  if (GetParam() == "treadmill") {
    EXPECT_GT(r.contacts.belt, 0);
  }
  if (GetParam() == "step_up" || GetParam() == "obstacle") {
    EXPECT_GT(r.contacts.wall, 0) << "no wall contact";
  }

  check_blocks(s, r, GetParam());
}

INSTANTIATE_TEST_SUITE_P(EveryEnvironment, Gradient, ::testing::ValuesIn(config::environment_names()),
                         [](const auto& info) { return info.param; });

// connectors.damping: the connector springs' dashpots (SPEC §2.2's −c_s((v_i − v_j)·d̂)d̂, the adjoint's DASHPOTS
// branch) on a short pair episode, flat and step_up, every block against central differences (rel. 1e-4, or a
// one-sided difference to 1e-3 where a contact branch flips inside the step); c_s = 20/s changes the episode
TEST(Gradient, ConnectorDashpotsMatchCentralDifferences) {
  for (const char* env : {"flat", "step_up"}) {
    sim::Scene s = pair_in(env);
    const sim::Scene plain = s;
    for (int sp : s.connector_spring_index) s.damping[sp] = 20.0;
    sim::RunOptions opt;
    opt.steps = kSteps;
    opt.grad = true;
    const sim::RunResult r = sim::simulate(s, opt);
    ASSERT_EQ(r.status, sim::Status::ok) << r.message;
    EXPECT_NE(r.travel, sim::simulate(plain, opt).travel) << "the dashpots change nothing";
    check_blocks(s, r, std::string(env) + " damped");
  }
}

// connectors.network = joint: one 55 → 32 → 32 → 5 network per connector (the same inputs, one column per connector);
// every block against central differences on flat and step_up, with a random joint network at the scene command's
// output gain (3), which moves the pair away from the per-spring network's episode
TEST(Gradient, JointConnectorNetworkMatchesCentralDifferences) {
  for (const char* env : {"flat", "step_up"}) {
    sim::Scene s = pair_in(env);
    const sim::Scene per_spring = s;
    Rng rng = make_rng(11, 3, 0);
    s.connector_params = morph::init_connector_params(rng, morph::kConnectorInitGains[2], /*joint=*/true);
    ASSERT_EQ(static_cast<int>(s.connector_params.size()), sim::connector_param_count(true));
    sim::RunOptions opt;
    opt.steps = kSteps;
    opt.grad = true;
    const sim::RunResult r = sim::simulate(s, opt);
    ASSERT_EQ(r.status, sim::Status::ok) << r.message;
    ASSERT_EQ(r.grad_connector_params.size(), s.connector_params.size());
    EXPECT_NE(r.travel, sim::simulate(per_spring, opt).travel);
    check_blocks(s, r, std::string(env) + " joint", /*nonzero=*/true);
  }
}

// the scene `s` dropped 0.05 u: the landing goes through the time of impact, and the gradient with respect to
// the start positions (the drop height among them) matches finite differences
void check_landing(sim::Scene s, const std::string& label) {
  for (int i = 0; i < s.n_masses(); ++i) s.x0[2 * i + 1] += 0.05;
  sim::RunOptions opt;
  opt.steps = kSteps;
  opt.grad = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << label;
  EXPECT_GT(r.contacts.toi, 0) << label;
  const std::vector<double> d = direction(s.x0.size(), 9);
  const Differences n = fd(s, d, 1e-7, [](sim::Scene& sc, const std::vector<double>& dd, double e) {
    for (size_t i = 0; i < sc.x0.size(); ++i) sc.x0[i] += e * dd[i];
  });
  EXPECT_TRUE(agrees(dot(r.grad_x0, d), n)) << label;
}

// a body dropped from above lands through the time of impact
TEST(Gradient, LandingThroughTimeOfImpact) {
  check_landing(collective::agent_scene(testing::gradient_pair().p, "flat", testing::kCoulomb), "coulomb");
}

// ---- the no_slip contact law (run.contact = "no_slip", src/MODEL.md "Contact laws") ----------------------
// the same checks under DiffTaichi's no-slip contact: the environment's own kappa_ns (0 but ice's 1/3), and
// kappa_ns = 0.5 too, so that the tangential retention's adjoint is exercised with and without a belt and at
// walls. Masses resting exactly on the ground are left out of the x0 direction as above. With kappa_ns = 0 a
// foot on the ground cannot move, and this untrained pair never reaches a wall in 150 steps however close the
// step is; with kappa_ns = 0.5 and the step 0.0003 u ahead it does (wall contact with kappa_ns = 0 is in
// stages_test.cpp)
struct NoSlipCase {
  std::string env;
  double keep;            // kappa_ns; < 0: the environment's own
  double back = 0.047;    // the features start 0.05 − back u ahead of the front
  bool walls = false;     // wall contacts expected
};
void PrintTo(const NoSlipCase& c, std::ostream* os) { *os << c.env << ", kappa_ns " << c.keep; }
class NoSlipGradient : public ::testing::TestWithParam<NoSlipCase> {};

sim::Scene no_slip(sim::Scene s, double keep) {
  s.env.contact = sim::ContactLaw::no_slip;
  if (keep >= 0) s.env.no_slip_keep = keep;
  return s;
}

TEST_P(NoSlipGradient, AllFourBlocksMatchCentralDifferences) {
  const NoSlipCase& c = GetParam();
  const sim::Scene s = no_slip(pair_in(c.env, c.back), c.keep);
  sim::RunOptions opt;
  opt.steps = kSteps;
  opt.grad = true;
  const sim::RunResult r = sim::simulate(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok) << r.message;
  EXPECT_GT(r.contacts.floor, 0);
  EXPECT_GT(r.contacts.toi, 0);
  // the retention term is live exactly when kappa_ns > 0
  if (s.env.no_slip_keep > 0) {
    EXPECT_GT(r.contacts.sliding, 0);
  } else {
    EXPECT_EQ(r.contacts.sliding, 0);
  }
  if (c.env == "treadmill") {
    EXPECT_GT(r.contacts.belt, 0);
  }
  if (c.walls) {
    EXPECT_GT(r.contacts.wall, 0) << "no wall contact";
  }
  check_blocks(s, r, c.env + " kappa_ns " + std::to_string(s.env.no_slip_keep), true);
}

INSTANTIATE_TEST_SUITE_P(Environments, NoSlipGradient,
                         ::testing::Values(NoSlipCase{"flat", -1}, NoSlipCase{"flat", 0.5}, NoSlipCase{"ice", -1},
                                           NoSlipCase{"treadmill", -1}, NoSlipCase{"treadmill", 0.5},
                                           NoSlipCase{"step_up", -1}, NoSlipCase{"step_up", 0.5, 0.0497, true},
                                           NoSlipCase{"obstacle", -1}, NoSlipCase{"obstacle", 0.5, 0.0497, true},
                                           NoSlipCase{"sticky", -1},
                                           NoSlipCase{"sand", -1}),
                         [](const auto& info) {
                           return info.param.env + (info.param.keep < 0 ? std::string("_own_keep") : "_keep_half");
                         });

// a body dropped from above lands under no_slip (kappa_ns = 0 and 0.5): the gradient w.r.t. x0 through the
// time of impact matches finite differences
TEST(NoSlipGradient, LandingThroughTimeOfImpact) {
  for (double keep : {0.0, 0.5})
    check_landing(no_slip(collective::agent_scene(testing::gradient_pair().p, "flat", testing::kCoulomb), keep),
                  "kappa_ns " + std::to_string(keep));
}

}  // namespace
}  // namespace divcoll
