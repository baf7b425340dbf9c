// the behaviour series of the DTW adversity (SPEC §8.1): positions relative to the agent's centre of mass,
// every k-th step, in the agent's own mass order
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/behaviour.hpp"
#include "common/check.hpp"
#include "collective/builders.hpp"
#include "collective/pairs.hpp"
#include "testing.hpp"

namespace divcoll::analysis {
namespace {

TEST(Behaviour, FramesAreCentredPositionsEveryKthStep) {
  const morph::Agent a = testing::agent_with_anchors(5, 77);
  const sim::Scene s = collective::agent_scene(a, "flat", testing::kCoulomb);
  sim::Simulator sim;
  sim::RunOptions opt;
  opt.steps = 95;
  opt.record = true;
  const sim::RunResult r = sim.run(s, opt);
  ASSERT_EQ(r.status, sim::Status::ok);
  const std::vector<double> b = agent_behaviour(s, r, 0, 10);
  ASSERT_EQ(b.size(), 10u * kBehaviourFeatures);  // steps 0, 10, ..., 90
  const int N = s.n_masses();
  for (int f = 0; f < 10; ++f) {
    double cx = 0, cy = 0, m = 0;
    for (int k = 0; k < 11; ++k) {
      const int i = s.agent_mass_index[k];
      cx += s.mass[i] * b[f * 22 + 2 * k], cy += s.mass[i] * b[f * 22 + 2 * k + 1], m += s.mass[i];
      // the same relative position as in the recorded trajectory
      const double* x = &r.x[static_cast<size_t>(f) * 10 * N * 2];
      const double dx = x[2 * i] - x[2 * s.agent_mass_index[0]], dy = x[2 * i + 1] - x[2 * s.agent_mass_index[0] + 1];
      EXPECT_NEAR(b[f * 22 + 2 * k] - b[f * 22], dx, 1e-12);
      EXPECT_NEAR(b[f * 22 + 2 * k + 1] - b[f * 22 + 1], dy, 1e-12);
    }
    EXPECT_NEAR(cx / m, 0.0, 1e-12) << "frame " << f;
    EXPECT_NEAR(cy / m, 0.0, 1e-12) << "frame " << f;
  }
}

TEST(Behaviour, PairSlotsAreTheTwoAgentsAndAloneMatchesItsOwnScene) {
  const morph::Agent a = testing::agent_with_anchors(5, 78), c = testing::agent_with_anchors(5, 79);
  const std::vector<double> w(sim::connector_param_count(), 0.0);
  const sim::Scene s = collective::pair_scene(a, c, w, testing::weak_connector(), "flat", testing::kCoulomb);
  sim::Simulator sim;
  sim::RunOptions opt;
  opt.steps = 40;
  opt.record = true;
  const sim::RunResult r = sim.run(s, opt);
  // frame 0: each slot's shape is its agent's own initial shape (placement only translates)
  const sim::Scene sa = collective::agent_scene(a, "flat", testing::kCoulomb), sc = collective::agent_scene(c, "flat", testing::kCoulomb);
  sim::RunOptions zero = opt;
  zero.steps = 1;
  const sim::RunResult ra = sim.run(sa, zero), rc = sim.run(sc, zero);
  const auto b0 = agent_behaviour(s, r, 0, 10), b1 = agent_behaviour(s, r, 1, 10);
  const auto ba = agent_behaviour(sa, ra, 0, 1), bc = agent_behaviour(sc, rc, 0, 1);
  for (int q = 0; q < 22; ++q) {
    EXPECT_NEAR(b0[q], ba[q], 1e-12);
    EXPECT_NEAR(b1[q], bc[q], 1e-12);
  }
  // not-ok runs give no behaviour; a scene without a recording is refused
  sim::RunResult bad = r;
  bad.status = sim::Status::nan;
  EXPECT_TRUE(agent_behaviour(s, bad, 0, 10).empty());
  sim::RunOptions plain;
  plain.steps = 5;
  EXPECT_THROW(agent_behaviour(s, sim.run(s, plain), 0, 10), divcoll::InputError);
  EXPECT_THROW(agent_behaviour(s, r, 2, 10), divcoll::InputError);
}

}  // namespace
}  // namespace divcoll::analysis
