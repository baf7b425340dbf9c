// what a tether does to each agent of a pair (collective/tether_effect.hpp): no springs, no push, and each agent walks
// as it does alone; any tether's two pushes cancel; a held tether pushes
#include "collective/tether_effect.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "collective/pairs.hpp"
#include "collective/references.hpp"
#include "config/config.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

const sim::RunPhysics kPhysics{};

TEST(TetherEffect, TheFreeTetherPushesNothingAndEachAgentWalksAsAlone) {
  const auto& cfg = config::default_config();
  const morph::Agent p = testing::agent_with_anchors(11, 3), a = testing::agent_with_anchors(12, 3);
  const collective::ReferenceConnector free = collective::reference_connector(cfg.connectors, "free");
  sim::Simulator sim;
  const collective::TetherEffect e = collective::tether_effect(sim, p, a, free.weights, free.tether, "flat", kPhysics, 400);
  ASSERT_EQ(e.status, sim::Status::ok);
  for (int q = 0; q < 2; ++q) {
    EXPECT_EQ(e.impulse_x[q], 0.0);
    EXPECT_EQ(e.work[q], 0.0);
  }
  EXPECT_EQ(e.force_time, 0.0);
  const double alone_p = collective::run_alone(sim, p, "flat", kPhysics, 400).travel_bl;
  const double alone_a = collective::run_alone(sim, a, "flat", kPhysics, 400).travel_bl;
  EXPECT_GT(std::abs(alone_p - alone_a), 1e-3) << "two different agents: the test should tell them apart";
  EXPECT_NEAR(e.travel_bl[0], alone_p, 1e-9);
  EXPECT_NEAR(e.travel_bl[1], alone_a, 1e-9);
  // the pair's centre of mass is the mean of its agents' (11 masses each)
  const double bp = morph::body_length(p), ba = morph::body_length(a);
  EXPECT_NEAR(e.pair_travel_bl * (bp + ba) / 2, (e.travel_bl[0] * bp + e.travel_bl[1] * ba) / 2, 1e-12);
}

TEST(TetherEffect, AHeldTetherPushesItsTwoAgentsEquallyAndOppositely) {
  const auto& cfg = config::default_config();
  const morph::Agent p = testing::agent_with_anchors(13, 3), a = testing::agent_with_anchors(14, 3);
  const collective::ReferenceConnector passive = collective::reference_connector(cfg.connectors, "passive");
  sim::Simulator sim;
  const collective::TetherEffect e =
      collective::tether_effect(sim, p, a, passive.weights, passive.tether, "flat", kPhysics, 400);
  ASSERT_EQ(e.status, sim::Status::ok);
  EXPECT_GT(e.force_time, 1e-3);
  EXPECT_GT(std::abs(e.impulse_x[0]), 1e-6);
  EXPECT_EQ(e.impulse_x[0], -e.impulse_x[1]);
  // the pair's own travel is the deploy stage's number for the same episode
  const double deployed = collective::run_pair(sim, p, a, passive.weights, passive.tether, "flat", kPhysics, 400, false).travel_bl;
  EXPECT_EQ(e.pair_travel_bl, deployed);
}

}  // namespace
}  // namespace divcoll
