// the readings a study varies in how collectives are built and deployed (src/collective/deploy_variants.hpp):
// a connector's springs from the config, uniform deployment pairs on training or held-out agents, feature
// offsets of agents alone
#include <gtest/gtest.h>

#include "collective/deploy_variants.hpp"
#include "common/check.hpp"
#include "config/config.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

TEST(Tether, EachKindGetsItsStrengthsStiffnessAndTheConfigsAmplitude) {
  const config::RunConfig d = config::default_config();
  EXPECT_EQ(collective::tether(d.connectors, "weak_uniform").stiffness, d.connectors.weak_stiffness);
  EXPECT_EQ(collective::tether(d.connectors, "strong_diverse").stiffness, d.connectors.strong_stiffness);
  EXPECT_EQ(collective::tether(d.connectors, "weak_diverse").amplitude, d.connectors.amplitude);
  const config::RunConfig c = config::apply_overrides(
      d, {"connectors.amplitude=0.3", "connectors.weak_stiffness=700", "connectors.strong_stiffness=9000"});
  for (const char* kind : {"weak_uniform", "weak_diverse", "strong_uniform", "strong_diverse"})
    EXPECT_EQ(collective::tether(c.connectors, kind).amplitude, 0.3) << kind;
  EXPECT_EQ(collective::tether(c.connectors, "weak_diverse").stiffness, 700.0);
  EXPECT_EQ(collective::tether(c.connectors, "strong_uniform").stiffness, 9000.0);
  EXPECT_EQ(collective::strength_tether(c.connectors, "weak").stiffness, 700.0);
  EXPECT_EQ(collective::strength_tether(c.connectors, "strong").amplitude, 0.3);
  // connectors.damping: every kind's dashpot, 0 by default (SPEC §6.2)
  EXPECT_EQ(collective::tether(d.connectors, "weak_uniform").damping, 0.0);
  const config::RunConfig damped = config::apply_overrides(d, {"connectors.damping=12.5"});
  for (const char* kind : {"weak_uniform", "weak_diverse", "strong_uniform", "strong_diverse"})
    EXPECT_EQ(collective::tether(damped.connectors, kind).damping, 12.5) << kind;
  EXPECT_EQ(collective::strength_tether(damped.connectors, "weak").damping, 12.5);
  // connectors.follower: no stiffness for any kind, the rest kept
  const config::RunConfig follow = config::apply_overrides(damped, {"connectors.follower=true"});
  for (const char* kind : {"weak_uniform", "weak_diverse", "strong_uniform", "strong_diverse"}) {
    EXPECT_EQ(collective::tether(follow.connectors, kind).stiffness, 0.0) << kind;
    EXPECT_EQ(collective::tether(follow.connectors, kind).damping, 12.5) << kind;
    EXPECT_EQ(collective::tether(follow.connectors, kind).amplitude, d.connectors.amplitude) << kind;
  }
  EXPECT_EQ(collective::strength_tether(follow.connectors, "strong").stiffness, 0.0);
  EXPECT_THROW(collective::tether(c.connectors, "medium_uniform"), InputError);
  EXPECT_THROW(collective::strength_tether(c.connectors, "medium"), InputError);
}

TEST(DeployUniformPairs, HeldOutAgentsFollowTheTrainingBatchAndNeverMeetIt) {
  const config::RunConfig c = config::apply_overrides(config::default_config(),
                                              {"agents.population=120", "connectors.batch_pairs=5", "deploy.pairs=20"});
  const auto training = collective::deploy_uniform_pairs(c.deploy, c.connectors);
  ASSERT_EQ(training.size(), 20u);
  for (size_t q = 0; q < training.size(); ++q) EXPECT_EQ(training[q], std::make_pair(int(q), int(q)));
  const config::RunConfig h = config::apply_overrides(c, {"deploy.uniform_agents=held_out"});
  const auto held = collective::deploy_uniform_pairs(h.deploy, h.connectors);
  ASSERT_EQ(held.size(), 20u);
  for (size_t q = 0; q < held.size(); ++q) {
    EXPECT_EQ(held[q].first, held[q].second);
    EXPECT_GE(held[q].first, 5) << "an agent of the uniform training batch";
    EXPECT_LT(held[q].first, 25);
  }
}

}  // namespace
}  // namespace divcoll
