// the graded-diversity stage's pieces (stages/graded.hpp): its body, its populations' config and its deployment
// plan, through the serial farm
#include "stages/graded.hpp"

#include <gtest/gtest.h>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "morph/body.hpp"
#include "stages/stage_testing.hpp"

namespace divcoll::stages {
namespace {

evo::Individual with(uint32_t cells, uint32_t springs) {
  evo::Individual x;
  x.agent.cells = cells, x.agent.springs = springs;
  return x;
}

TEST(Graded, TheShapeIsTheCommonestBodyAndItsCommonestSprings) {
  // body 9 three times (springs 5, 5, 4), body 3 three times: a tie goes to the lowest genotype
  const std::vector<evo::Individual> main = {with(9, 5), with(3, 1), with(9, 4), with(3, 2), with(9, 5), with(3, 2),
                                             with(1, 7)};
  const GradedShape s = graded_shape(main);
  EXPECT_EQ(s.cells, 3u);
  EXPECT_EQ(s.springs, 2u);
  const GradedShape t = graded_shape({with(9, 5), with(9, 4), with(9, 5), with(3, 1)});
  EXPECT_EQ(t.cells, 9u);
  EXPECT_EQ(t.springs, 5u);
}

TEST(Graded, ThePopulationsEvolveOneBodyAndTheSecondOneSpringGenotypeWithoutEvolution) {
  const config::RunConfig cfg = test::tiny({"agents.episode_steps=40", "agents.epochs=1", "graded.population=3",
                                        "agents.uniqueness_k=2"});
  Rng rng = make_rng(8, 8, 8);
  const morph::Agent body = collective::random_agent(rng);
  const GradedShape shape{body.cells, body.springs};
  const auto [def0, spec0] = graded_agents(graded_def(cfg), 0, shape);
  EXPECT_EQ(spec0.group, "graded/same_shape/agents");
  EXPECT_EQ(def0.agents.population, 3);
  EXPECT_EQ(def0.agents.generations, cfg.agents.generations);
  EXPECT_TRUE(def0.agents.body_fixed);
  EXPECT_FALSE(def0.agents.rest_moves);
  EXPECT_EQ(spec0.fixed_springs, 0u);
  const auto [def1, spec1] = graded_agents(graded_def(cfg), 1, shape);
  EXPECT_EQ(spec1.group, "graded/same_shape_springs/agents");
  EXPECT_EQ(spec1.stream, kGradedStage + 100000);
  EXPECT_EQ(def1.agents.generations, 0);
  EXPECT_EQ(def1.agents.epochs, (cfg.agents.generations + 1) * cfg.agents.epochs);  // a lineage's gradient budget
  // population 1 through the agents plan: every agent has the body and the springs
  const auto plan = make_agents_plan(def1, spec1, {});
  const test::Datasets d = test::written(run_serial(*plan));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(test::at(d, "graded/same_shape_springs/agents/final/cells").values[i], body.cells);
    EXPECT_EQ(test::at(d, "graded/same_shape_springs/agents/final/springs").values[i], body.springs);
  }
}

TEST(Graded, TheDeploymentRecordsAgentsAloneAndPairsInEveryEnvironment) {
  const config::RunConfig cfg = test::tiny({"deploy.environments=flat,gap", "deploy.episode_steps=60", "deploy.pairs=2",
                                        "graded.population=3", "connectors.replicates=1", "agents.uniqueness_k=2"});
  const std::vector<morph::Agent> agents = test::random_population(3, 9);
  Rng wr = make_rng(2, 2, 2);
  const std::vector<std::vector<double>> weights = {morph::init_connector_params(wr, morph::kConnectorInitGains[2])};
  const std::vector<std::pair<int, int>> pairs = {{0, 2}, {1, 0}};
  auto make = [&] { return make_graded_deploy_plan(graded_def(cfg), 0, agents, weights, pairs); };
  const SerialRun run = run_serial(*make());
  EXPECT_EQ(run.items, 2 * (3 + 2));
  const test::Datasets d = test::written(run);
  EXPECT_EQ(test::at(d, "graded/same_shape/deploy/agents/travel_u").dims, (std::vector<uint64_t>{2, 3}));
  EXPECT_EQ(test::at(d, "graded/same_shape/deploy/pairs/travel_u").dims, (std::vector<uint64_t>{2, 1, 2}));
  sim::Simulator sim;
  for (int e = 0; e < 2; ++e) {
    const std::string& env = cfg.deploy.environments[e];
    for (int i = 0; i < 3; ++i)
      EXPECT_TRUE(test::same_bits(test::at(d, "graded/same_shape/deploy/agents/travel_u").values[e * 3 + i],
                                  collective::run_alone(sim, agents[i], env, sim::RunPhysics{}, cfg.deploy.episode_steps).travel_u));
    for (int q = 0; q < 2; ++q)
      EXPECT_TRUE(test::same_bits(
          test::at(d, "graded/same_shape/deploy/pairs/travel_u").values[e * 2 + q],
          collective::run_pair(sim, agents[pairs[q].first], agents[pairs[q].second], weights[0],
                               collective::tether(cfg.connectors, "weak_diverse"), env, sim::RunPhysics{}, cfg.deploy.episode_steps, false)
              .travel_u));
  }
  SerialOptions o;
  o.rounds_per_farm = 2;
  o.order = SerialOptions::Order::reversed;
  test::expect_same(test::written(run_serial(*make(), o)), d);
}


TEST(Graded, TheDriverAndTheSerialFarmMakeTheSameFarmCallsOfItsPopulationsAndTheirDeployment) {
  const config::RunConfig cfg = test::tiny({"deploy.environments=flat,gap", "deploy.episode_steps=60", "deploy.pairs=2",
                                        "graded.population=3", "connectors.replicates=1", "agents.uniqueness_k=2",
                                        "agents.episode_steps=40", "agents.epochs=1", "agents.generations=1"});
  // the populations through the agents plan
  Rng rng = make_rng(8, 8, 8);
  const morph::Agent body = collective::random_agent(rng);
  for (int v : {0, 1}) {
    SCOPED_TRACE("population " + std::to_string(v));
    const auto [def, spec] = graded_agents(graded_def(cfg), v, GradedShape{body.cells, body.springs});
    test::expect_driver_and_serial_calls_agree([&] { return make_agents_plan(def, spec, {}); });
  }
  // their deployment
  const std::vector<morph::Agent> agents = test::random_population(3, 9);
  Rng wr = make_rng(2, 2, 2);
  const std::vector<std::vector<double>> weights = {morph::init_connector_params(wr, morph::kConnectorInitGains[2])};
  const std::vector<std::pair<int, int>> pairs = {{0, 2}, {1, 0}};
  auto make = [&] { return make_graded_deploy_plan(graded_def(cfg), 0, agents, weights, pairs); };
  test::expect_driver_and_serial_calls_agree(make);
  test::expect_resumed_calls_agree(make, 1);
}

}  // namespace
}  // namespace divcoll::stages
