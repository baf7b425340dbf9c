// the deployment's plan (stages/deploy.hpp) through the serial farm: two environments, a few agents and pairs
#include "stages/deploy.hpp"

#include <gtest/gtest.h>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "collective/references.hpp"
#include "morph/body.hpp"
#include "stages/stage_testing.hpp"

namespace divcoll::stages {
namespace {

struct Case {
  config::RunConfig cfg = test::tiny({"deploy.environments=flat,ice", "deploy.episode_steps=80", "deploy.pairs=3",
                                  "deploy.early_step=20", "deploy.hidden_subsample=30",
                                  "connectors.kinds=weak_uniform,weak_diverse"});
  std::vector<morph::Agent> agents = test::random_population(4);
  DeployTypes types() const {
    DeployTypes t;
    for (const std::string& kind : cfg.connectors.kinds) {
      Rng rng = make_rng(3, 3, kind.size());
      const std::vector<std::vector<double>> reps = {morph::init_connector_params(rng, morph::kConnectorInitGains[2])};
      for (const char* dep : {"uniform", "diverse"}) {
        t.names.push_back(kind + "@" + dep);
        t.weights.push_back(reps);
        t.tethers.push_back(collective::tether(cfg.connectors, kind));
        t.diverse.push_back(std::string(dep) == "diverse");
      }
    }
    return t;
  }
  std::unique_ptr<Plan> plan() const { return make_deploy_plan(deploy_def(cfg), agents, types()); }
};

TEST(DeployPlan, RecordsEveryEnvironmentsAgentsCollectivesAndHiddenStates) {
  const Case c;
  const SerialRun run = run_serial(*c.plan());
  const uint64_t E = 2, P = 4, T = 4, R = 1, N = 3, K = 10;  // K = ceil(hidden_subsample / pairs)
  EXPECT_EQ(run.done, 2);
  EXPECT_EQ(run.items, static_cast<int64_t>(E * (P + T * R * N)));
  const test::Datasets d = test::written(run);
  EXPECT_EQ(test::at(d, "deploy/diverse_pairs").dims, (std::vector<uint64_t>{N, 2}));
  for (const char* s : {"travel_u", "travel_bl", "status", "travel_bl_early"}) {
    EXPECT_EQ(test::at(d, std::string("deploy/agents/") + s).dims, (std::vector<uint64_t>{E, P})) << s;
    EXPECT_EQ(test::at(d, std::string("deploy/collectives/") + s).dims, (std::vector<uint64_t>{E, T, R, N})) << s;
  }
  for (const char* t : {"weak_uniform@uniform", "weak_diverse@diverse"}) {
    EXPECT_EQ(test::at(d, std::string("deploy/hidden/") + t + "/states").dims, (std::vector<uint64_t>{E, R, N, K, 32}));
    EXPECT_EQ(test::at(d, std::string("deploy/hidden/") + t + "/index").dims, (std::vector<uint64_t>{E, R, N, K}));
  }
  EXPECT_EQ(d.count("deploy/hidden/weak_uniform@diverse/states"), 0u);  // only the weak connectors as trained
  EXPECT_EQ(d.count("deploy/hidden/weak_uniform@uniform/inputs"), 0u);  // only with familiarity_on = inputs
}

TEST(DeployPlan, EachEpisodeIsTheDirectSimulationOfItsAgentOrPair) {
  const Case c;
  const test::Datasets d = test::written(run_serial(*c.plan()));
  const DeployTypes types = c.types();
  sim::Simulator sim;
  sim::RunOptions opt;
  opt.steps = c.cfg.deploy.episode_steps;
  opt.record = true;  // deploy.early_step > 0
  const auto uniform = collective::deploy_uniform_pairs(c.cfg.deploy, c.cfg.connectors);
  const std::vector<double>& pairs = test::at(d, "deploy/diverse_pairs").values;
  for (int e = 0; e < 2; ++e) {
    const std::string& env = c.cfg.deploy.environments[e];
    for (int i = 0; i < 4; ++i) {
      sim::RunResult full;
      const auto o = collective::run_alone(sim, c.agents[i], env, sim::ContactLaw::coulomb, opt, &full,
                                           collective::alone_feature_offset(c.cfg.deploy, c.agents[i]));
      EXPECT_TRUE(test::same_bits(test::at(d, "deploy/agents/travel_u").values[e * 4 + i], o.travel_u)) << env << i;
    }
    for (int t = 0; t < 4; ++t)
      for (int q = 0; q < 3; ++q) {
        const int a = types.diverse[t] ? static_cast<int>(pairs[2 * q]) : uniform[q].first;
        const int b = types.diverse[t] ? static_cast<int>(pairs[2 * q + 1]) : uniform[q].second;
        const auto o = collective::run_pair(sim, c.agents[a], c.agents[b], types.weights[t][0], types.tethers[t], env,
                                            sim::ContactLaw::coulomb, opt, nullptr);
        EXPECT_TRUE(test::same_bits(test::at(d, "deploy/collectives/travel_u").values[(e * 4 + t) * 3 + q], o.travel_u))
            << env << " " << types.names[t] << " " << q;
      }
  }
}

TEST(DeployPlan, ReferenceConnectorsAreRecordedBesideAndDoNotChangeTheTrainedTypes) {
  const Case plain;
  Case refs;
  refs.cfg = config::apply_overrides(refs.cfg, {"deploy.references=true"});
  const test::Datasets without = test::written(run_serial(*plain.plan()));
  const SerialRun run = run_serial(*refs.plan());
  const test::Datasets with = test::written(run);
  const uint64_t E = 2, P = 4, T = 4, R = 1, N = 3, RT = 6;  // free, passive, follower × uniform, diverse
  EXPECT_EQ(run.items, static_cast<int64_t>(E * (P + T * R * N + RT * N)));
  for (const char* s : {"travel_u", "travel_bl", "status", "travel_bl_early"})
    EXPECT_EQ(test::at(with, std::string("deploy/references/") + s).dims, (std::vector<uint64_t>{E, RT, N})) << s;
  // every dataset of the run without references has the same bits with them
  for (const auto& [path, ds] : without) {
    ASSERT_EQ(with.count(path), 1u) << path;
    EXPECT_EQ(test::at(with, path).dims, ds.dims) << path;
    for (size_t i = 0; i < ds.values.size(); ++i)
      ASSERT_TRUE(test::same_bits(test::at(with, path).values[i], ds.values[i])) << path << " [" << i << "]";
  }
  // free on clones is each agent alone: on flat (no feature) the pair travels as its agent does alone
  const auto uniform = collective::deploy_uniform_pairs(refs.cfg.deploy, refs.cfg.connectors);
  const std::vector<double>& ref_u = test::at(with, "deploy/references/travel_u").values;
  const std::vector<double>& alone_u = test::at(with, "deploy/agents/travel_u").values;
  for (uint64_t q = 0; q < N; ++q) {
    const double pair = ref_u[(0 * RT + 0) * N + q], alone = alone_u[0 * P + uniform[q].first];  // flat, free@uniform
    EXPECT_NEAR(pair, alone, 1e-9 * (1 + std::abs(alone))) << "pair " << q;
  }
  // each reference episode is the direct simulation of its pair with the reference's weights and tether
  sim::Simulator sim;
  sim::RunOptions opt;
  opt.steps = refs.cfg.deploy.episode_steps;
  opt.record = true;
  const std::vector<double>& pairs = test::at(with, "deploy/diverse_pairs").values;
  for (uint64_t rt = 0; rt < RT; ++rt) {
    const auto ref = collective::reference_connector(refs.cfg.connectors, collective::kReferenceConnectors[rt / 2]);
    for (uint64_t q = 0; q < N; ++q) {
      const int a = rt % 2 ? static_cast<int>(pairs[2 * q]) : uniform[q].first;
      const int b = rt % 2 ? static_cast<int>(pairs[2 * q + 1]) : uniform[q].second;
      const auto o = collective::run_pair(sim, refs.agents[a], refs.agents[b], ref.weights, ref.tether, "ice",
                                          sim::ContactLaw::coulomb, opt, nullptr);
      EXPECT_TRUE(test::same_bits(ref_u[(1 * RT + rt) * N + q], o.travel_u)) << rt << " " << q;
    }
  }
}

TEST(DeployPlan, AWorkersPlanAnyComputeOrderAndAResumeGiveTheSameRows) {
  const Case c;
  const test::Datasets want = test::written(run_serial(*c.plan()));
  for (auto order : {SerialOptions::Order::dearest_first, SerialOptions::Order::reversed}) {
    const auto master = c.plan(), worker = c.plan();
    SerialOptions o;
    o.order = order;
    test::expect_same(test::written(run_serial(*master, o, worker.get())), want);
  }
  test::expect_same(test::resumed([&] { return c.plan(); }, 1), want);
}


TEST(DeployPlan, TheDriverAndTheSerialFarmMakeTheSameFarmCalls) {
  const Case c;
  auto make = [&] { return c.plan(); };
  test::expect_driver_and_serial_calls_agree(make);
  test::expect_resumed_calls_agree(make, 1);
}

}  // namespace
}  // namespace divcoll::stages
