// the scaling chains' plan (stages/scaling.hpp) through the serial farm
#include "stages/scaling.hpp"

#include <gtest/gtest.h>

#include <set>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "morph/body.hpp"
#include "stages/stage_testing.hpp"

namespace divcoll::stages {
namespace {

struct Case {
  config::RunConfig cfg = test::tiny({"deploy.environments=flat,ice", "scaling.sizes=2,3", "scaling.draws=2",
                                  "scaling.episode_steps=60", "connectors.replicates=1"});
  std::vector<morph::Agent> agents = test::random_population(4);
  std::vector<std::vector<double>> weights;  // weak uniform-trained, then weak diverse-trained
  Case() {
    for (uint64_t k = 0; k < 2; ++k) {
      Rng rng = make_rng(6, 6, k);
      weights.push_back(morph::init_connector_params(rng, morph::kConnectorInitGains[2]));
    }
  }
  std::unique_ptr<Plan> plan() const { return make_scaling_plan(scaling_def(cfg), agents, weights); }
};

TEST(ScalingPlan, RecordsTheChainsAndEveryEnvironmentsTravel) {
  const Case c;
  const SerialRun run = run_serial(*c.plan());
  const uint64_t E = 2, S = 2, R = 1, D = 2;
  EXPECT_EQ(run.items, static_cast<int64_t>(E * S * 2 * R * D));
  const test::Datasets d = test::written(run);
  EXPECT_EQ(test::at(d, "scaling/sizes").values, (std::vector<double>{2, 3}));
  for (int n : {2, 3}) {
    const Dataset& chains = test::at(d, "scaling/n" + std::to_string(n) + "/diverse_agents");
    EXPECT_EQ(chains.dims, (std::vector<uint64_t>{R * D, static_cast<uint64_t>(n)}));
    for (uint64_t k = 0; k < R * D; ++k) {  // distinct agents in each diverse chain
      const std::set<double> in(chains.values.begin() + k * n, chains.values.begin() + (k + 1) * n);
      EXPECT_EQ(in.size(), static_cast<size_t>(n));
    }
  }
  for (const char* s : {"travel_u", "travel_bl", "status"})
    EXPECT_EQ(test::at(d, std::string("scaling/") + s).dims, (std::vector<uint64_t>{E, S, 2, R, D}));
}

TEST(ScalingPlan, EachChainIsTheDirectSimulationOfItsAgents) {
  const Case c;
  const test::Datasets d = test::written(run_serial(*c.plan()));
  sim::Simulator sim;
  const collective::Tether tether = collective::tether(c.cfg.connectors, "weak_uniform");
  for (int e = 0; e < 2; ++e)
    for (int si = 0; si < 2; ++si) {
      const int n = si + 2;
      const Dataset& chains = test::at(d, "scaling/n" + std::to_string(n) + "/diverse_agents");
      for (int v = 0; v < 2; ++v)
        for (int q = 0; q < 2; ++q) {
          std::vector<const morph::Agent*> chain;
          for (int k = 0; k < n; ++k)
            chain.push_back(&c.agents[v == 0 ? q : static_cast<int>(chains.values[q * n + k])]);  // uniform: clones of `draw`
          const auto o = collective::run_chain(sim, chain, c.weights[v], tether, c.cfg.deploy.environments[e],
                                               sim::RunPhysics{}, c.cfg.scaling.episode_steps);
          const size_t at = ((static_cast<size_t>(e) * 2 + si) * 2 + v) * 2 + q;
          EXPECT_TRUE(test::same_bits(test::at(d, "scaling/travel_u").values[at], o.travel_u)) << e << si << v << q;
        }
    }
}

TEST(ScalingPlan, RoundsFarmedTogetherTheDearestFirstAndAResumeGiveTheSameRows) {
  const Case c;
  const test::Datasets want = test::written(run_serial(*c.plan()));
  const auto plan = c.plan(), worker = c.plan();
  SerialOptions o;
  o.rounds_per_farm = 2;
  o.order = SerialOptions::Order::dearest_first;
  test::expect_same(test::written(run_serial(*plan, o, worker.get())), want);
  test::expect_same(test::resumed([&] { return c.plan(); }, 1), want);
}


TEST(ScalingPlan, TheDriverAndTheSerialFarmMakeTheSameFarmCalls) {
  const Case c;
  auto make = [&] { return c.plan(); };
  test::expect_driver_and_serial_calls_agree(make);
  test::expect_resumed_calls_agree(make, 1);
}

}  // namespace
}  // namespace divcoll::stages
