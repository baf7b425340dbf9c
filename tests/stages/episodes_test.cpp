// the episodes plan (stages/episodes.hpp) that deploys the specialists and the graded populations, through the
// serial farm, set up as the specialists stage sets it up
#include "stages/episodes.hpp"

#include <gtest/gtest.h>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "morph/body.hpp"
#include "stages/specialists.hpp"
#include "stages/stage_testing.hpp"

namespace divcoll::stages {
namespace {

struct Case {
  config::RunConfig cfg = test::tiny({"deploy.episode_steps=60", "deploy.pairs=2", "specialists.replicates=2"});
  std::vector<morph::Agent> agents = test::random_population(4);
  std::vector<std::string> envs = novel_environments(cfg.deploy);
  std::vector<std::vector<double>> weights;  // environment · R + replicate
  std::vector<std::pair<int, int>> pairs = {{0, 1}, {2, 3}};
  Case() {
    for (size_t k = 0; k < envs.size() * 2; ++k) {
      Rng rng = make_rng(4, 4, k);
      weights.push_back(morph::init_connector_params(rng, morph::kConnectorInitGains[2]));
    }
  }
  std::unique_ptr<EpisodesPlan> plan() const {
    const int R = 2;
    auto round_items = [this, R](int e) {
      std::vector<GroupEpisode> eps;
      for (int r = 0; r < R; ++r)
        for (const auto& [a, b] : pairs) eps.push_back({e * R + r, e, {a, b}});
      return eps;
    };
    auto summary = [](int, const std::vector<EpisodeDone>& d) { return std::to_string(ok_mean(d, 0, d.size()).first); };
    return std::make_unique<EpisodesPlan>("specialists deploy", "specialists", agents, weights,
                                          collective::tether(cfg.connectors, "weak_diverse"), config::run_physics(cfg), envs, cfg.deploy.episode_steps,
                                          std::vector<EpisodesPlan::Part>{{"specialists", {2, 2}}}, round_items, summary);
  }
};

TEST(EpisodesPlan, NovelEnvironmentsAreEveryOneButFlat) {
  const Case c;
  EXPECT_EQ(c.envs, (std::vector<std::string>{"step_up", "gap", "ice"}));
}

TEST(EpisodesPlan, RecordsARowPerEnvironmentOfTheDirectPairEpisodes) {
  const Case c;
  const SerialRun run = run_serial(*c.plan());
  EXPECT_EQ(run.done, 3);
  const test::Datasets d = test::written(run);
  for (const char* s : {"/travel_u", "/travel_bl", "/status"})
    EXPECT_EQ(test::at(d, std::string("specialists") + s).dims, (std::vector<uint64_t>{3, 2, 2}));
  sim::Simulator sim;
  for (int e = 0; e < 3; ++e)
    for (int r = 0; r < 2; ++r)
      for (int q = 0; q < 2; ++q) {
        const auto o = collective::run_pair(sim, c.agents[c.pairs[q].first], c.agents[c.pairs[q].second],
                                            c.weights[e * 2 + r], collective::tether(c.cfg.connectors, "weak_diverse"), c.envs[e],
                                            sim::RunPhysics{}, c.cfg.deploy.episode_steps, false);
        EXPECT_TRUE(test::same_bits(test::at(d, "specialists/travel_u").values[(e * 2 + r) * 2 + q], o.travel_u));
        EXPECT_EQ(test::at(d, "specialists/status").values[(e * 2 + r) * 2 + q], static_cast<double>(o.status));
      }
}

TEST(EpisodesPlan, RoundsFarmedTogetherAnyComputeOrderAndAResumeGiveTheSameRows) {
  const Case c;
  const test::Datasets want = test::written(run_serial(*c.plan()));
  for (int together : {2, 3}) {
    const auto plan = c.plan();
    SerialOptions o;
    o.rounds_per_farm = together;
    o.order = SerialOptions::Order::shuffled;
    o.shuffle_seed = together;
    test::expect_same(test::written(run_serial(*plan, o)), want);
  }
  test::expect_same(test::resumed([&] { return c.plan(); }, 2), want);
}

TEST(EpisodesPlan, EpisodeCostsCountNetworksAndOkMeanLeavesFailuresOut) {
  EXPECT_EQ(episode_cost({0, 0, {1}}), 1.0);
  EXPECT_EQ(episode_cost({0, 0, {1, 2}}), 3.0);
  const std::vector<EpisodeDone> d = {{1, 2.0, 0}, {1, NAN, 1}, {1, 4.0, 0}};
  EXPECT_EQ(ok_mean(d, 0, 3), (std::pair<double, int>{3.0, 1}));
  Rng rng = make_rng(1, 1, 1);
  std::vector<int32_t> x = distinct_agents(rng, 6, 4);
  std::sort(x.begin(), x.end());
  EXPECT_EQ(std::unique(x.begin(), x.end()), x.end());
  EXPECT_EQ(x.size(), 4u);
}


TEST(EpisodesPlan, TheDriverAndTheSerialFarmMakeTheSameFarmCalls) {
  const Case c;
  auto make = [&] { return c.plan(); };
  test::expect_driver_and_serial_calls_agree(make);
  test::expect_resumed_calls_agree(make, 1);
}

}  // namespace
}  // namespace divcoll::stages
