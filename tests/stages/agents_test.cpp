// the agents stage's plan (stages/agents.hpp) through the serial farm, at a few agents and generations
#include "stages/agents.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "collective/builders.hpp"
#include "evo/gd.hpp"
#include "morph/descriptor.hpp"
#include "stages/stage_testing.hpp"

namespace divcoll::stages {
namespace {

constexpr int M11 = sim::kAgentMasses, S21 = sim::kAgentSprings;

config::RunConfig config() {
  return test::tiny({"agents.population=4", "agents.generations=2", "agents.epochs=1", "agents.episode_steps=60",
                     "agents.uniqueness_k=2"});
}

// the survivors of generation g as the runner reads them back from the run file (io::read_pool)
std::vector<evo::Individual> survivors(const test::Datasets& d, const std::string& group) {
  auto col = [&](const std::string& name) -> const std::vector<double>& { return test::at(d, group + "/" + name).values; };
  const size_t M = test::at(d, group + "/id").dims[0], P = test::at(d, group + "/params").dims[1];
  const size_t C = test::at(d, group + "/curve_u").dims[1];
  std::vector<evo::Individual> out;
  for (size_t i = 0; i < M; ++i) {
    if (col("survived")[i] == 0) continue;
    evo::Individual x;
    x.id = static_cast<int64_t>(col("id")[i]);
    x.parent = static_cast<int64_t>(col("parent")[i]);
    x.agent.cells = static_cast<uint32_t>(col("cells")[i]);
    x.agent.springs = static_cast<uint32_t>(col("springs")[i]);
    auto rows = [&](const std::string& name, size_t w, auto& into) {
      into.clear();
      for (size_t q = 0; q < w; ++q) into.push_back(static_cast<std::decay_t<decltype(into[0])>>(col(name)[i * w + q]));
    };
    rows("rest_pos", 2 * M11, x.agent.rest_pos);
    rows("spring_i", S21, x.agent.spring_i);
    rows("spring_j", S21, x.agent.spring_j);
    rows("rest_length", S21, x.agent.rest_length);
    rows("amplitude", S21, x.agent.amplitude);
    rows("params", P, x.agent.params);
    rows("curve_u", C, x.train.curve_u);
    x.train.fitness_bl = col("fitness")[i];
    x.train.travel_u = col("travel_u")[i];
    x.train.status = static_cast<sim::Status>(col("status")[i]);
    for (int q = 0; q < morph::kDescriptorSize; ++q) x.descriptor[q] = col("descriptor")[i * morph::kDescriptorSize + q];
    out.push_back(std::move(x));
  }
  return out;
}

TEST(AgentsPlan, RecordsEveryGenerationAndTheFinalPopulation) {
  const config::RunConfig cfg = config();
  const int P = cfg.agents.population, G = cfg.agents.generations;
  const auto plan = make_agents_plan(agents_def(cfg), AgentsSpec{}, {});
  EXPECT_EQ(plan->rounds(), G + 1);
  const SerialRun run = run_serial(*plan);
  EXPECT_EQ(run.done, G + 1);
  EXPECT_EQ(run.items, static_cast<int64_t>(P) * (G + 1));
  ASSERT_EQ(run.attributes.size(), 1u);
  EXPECT_EQ(std::get<int64_t>(run.attributes[0].value), P);
  const test::Datasets d = test::written(run);
  Rng any = make_rng(1, 2, 3);
  const uint64_t Pa = collective::random_agent(any).params.size();
  for (int g = 0; g <= G; ++g) {
    const std::string gen = gen_name("agents", g);
    const uint64_t M = g == 0 ? P : 2 * P;  // generation 0: the random agents; later: parents, then offspring
    EXPECT_EQ(test::at(d, gen + "/fitness").dims, std::vector<uint64_t>{M}) << gen;
    EXPECT_EQ(test::at(d, gen + "/params").dims, (std::vector<uint64_t>{M, Pa})) << gen;
    EXPECT_EQ(test::at(d, gen + "/rest_pos").dims, (std::vector<uint64_t>{M, M11, 2})) << gen;
    EXPECT_EQ(test::at(d, gen + "/curve_u").dims, (std::vector<uint64_t>{M, static_cast<uint64_t>(cfg.agents.epochs) + 1}));
    double survived = 0;
    for (double s : test::at(d, gen + "/survived").values) survived += s;
    EXPECT_EQ(survived, P) << gen;
    for (double id : test::at(d, gen + "/id").values) EXPECT_FALSE(std::isnan(id)) << gen;  // every row written
  }
  EXPECT_EQ(gen_name("graded/same_shape/agents", 7), "graded/same_shape/agents/gen_007");
  // the final population: the last generation's survivors
  EXPECT_EQ(test::at(d, "agents/final/fitness").dims, std::vector<uint64_t>{static_cast<uint64_t>(P)});
  const auto last = survivors(d, gen_name("agents", G));
  ASSERT_EQ(last.size(), static_cast<size_t>(P));
  for (int i = 0; i < P; ++i) EXPECT_EQ(test::at(d, "agents/final/id").values[i], last[i].id);
}

TEST(AgentsPlan, GenerationZeroIsEachRandomAgentTrainedByGradientDescent) {
  const config::RunConfig cfg = config();
  const auto plan = make_agents_plan(agents_def(cfg), AgentsSpec{}, {});
  const test::Datasets d = test::written(run_serial(*plan));
  evo::GdOptions gd = evo::gd_options(config::default_config().agents);
  gd.epochs = cfg.agents.epochs;
  gd.steps = cfg.agents.episode_steps;
  gd.rule = evo::gd_rule_from(cfg.agents.gd_rule);
  gd.step = cfg.agents.gd_step;
  gd.adam_lr = cfg.agents.adam_lr;
  gd.rest_moves = cfg.agents.rest_moves;
  gd.rest_move_max = cfg.agents.rest_move_max;
  gd.rest_length_min = cfg.agents.rest_length_min;
  gd.rest_length_max = cfg.agents.rest_length_max;
  sim::Simulator sim;
  const size_t Pa = test::at(d, "agents/gen_000/params").dims[1];
  for (int i = 0; i < cfg.agents.population; ++i) {
    Rng rng = make_rng(cfg.run.seed, kAgentsStage, static_cast<uint64_t>(i));
    morph::Agent a = collective::random_agent(rng);
    const evo::TrainResult t = evo::train_agent(a, gd, sim::RunPhysics{}, sim);
    EXPECT_TRUE(test::same_bits(test::at(d, "agents/gen_000/fitness").values[i], t.fitness_bl)) << i;
    EXPECT_TRUE(test::same_bits(test::at(d, "agents/gen_000/travel_u").values[i], t.travel_u)) << i;
    EXPECT_EQ(test::at(d, "agents/gen_000/cells").values[i], a.cells) << i;
    for (size_t q = 0; q < Pa; ++q)
      ASSERT_TRUE(test::same_bits(test::at(d, "agents/gen_000/params").values[i * Pa + q], a.params[q])) << i << " " << q;
    const morph::Descriptor desc = evo::agent_descriptor(a);
    for (int q = 0; q < morph::kDescriptorSize; ++q)
      EXPECT_TRUE(test::same_bits(test::at(d, "agents/gen_000/descriptor").values[i * morph::kDescriptorSize + q], desc[q]));
  }
}

TEST(AgentsPlan, AWorkersPlanAndAnyComputeOrderGiveTheSameGenerations) {
  const config::RunConfig cfg = config();
  const auto plain = make_agents_plan(agents_def(cfg), AgentsSpec{}, {});
  const test::Datasets want = test::written(run_serial(*plain));
  // a worker's plan has no population (the runner clears it on every rank but the master)
  for (auto order : {SerialOptions::Order::shuffled, SerialOptions::Order::dearest_first}) {
    const auto master = make_agents_plan(agents_def(cfg), AgentsSpec{}, {});
    const auto worker = make_agents_plan(agents_def(cfg), AgentsSpec{}, {});
    SerialOptions o;
    o.order = order;
    o.shuffle_seed = 11;
    test::expect_same(test::written(run_serial(*master, o, worker.get())), want);
  }
}

TEST(AgentsPlan, AResumeFromACommittedGenerationContinuesAsAnUninterruptedRun) {
  const config::RunConfig cfg = config();
  const auto plain = make_agents_plan(agents_def(cfg), AgentsSpec{}, {});
  const test::Datasets want = test::written(run_serial(*plain));
  for (int cut = 1; cut <= cfg.agents.generations; ++cut) {
    // the plan's state is its population, which the runner reads back from the last committed generation
    const auto first = make_agents_plan(agents_def(cfg), AgentsSpec{}, {});
    SerialOptions o;
    o.until = cut;
    const SerialRun a = run_serial(*first, o);
    const auto second = make_agents_plan(agents_def(cfg), AgentsSpec{}, survivors(test::written(a), gen_name("agents", cut - 1)));
    SerialOptions rest;
    rest.from = cut;
    const SerialRun b = run_serial(*second, rest);
    test::expect_same(datasets(std::vector<Records>{a.written(), b.written()}), want);
  }
}

TEST(AgentsPlan, AFixedBodyAndSpringsReachEveryAgentOfGenerationZero) {
  const config::RunConfig cfg = config();
  Rng rng = make_rng(5, 5, 5);
  const morph::Agent body = collective::random_agent(rng);
  AgentsSpec spec;
  spec.group = "graded/x/agents";
  spec.stream = 777;
  spec.fixed_cells = body.cells;
  spec.fixed_springs = body.springs;
  spec.spring_descriptor = true;
  AgentsDef def = agents_def(cfg);
  def.agents.generations = 0;
  const auto plan = make_agents_plan(def, spec, {});
  const test::Datasets d = test::written(run_serial(*plan));
  for (int i = 0; i < cfg.agents.population; ++i) {
    EXPECT_EQ(test::at(d, "graded/x/agents/gen_000/cells").values[i], body.cells);
    EXPECT_EQ(test::at(d, "graded/x/agents/gen_000/springs").values[i], body.springs);
  }
  EXPECT_EQ(d.count("graded/x/agents/final/params"), 1u);
}


TEST(AgentsPlan, TheDriverAndTheSerialFarmMakeTheSameFarmCalls) {
  const config::RunConfig cfg = config();
  auto make = [&] { return make_agents_plan(agents_def(cfg), AgentsSpec{}, {}); };
  test::expect_driver_and_serial_calls_agree(make);
  // resumed: the runner builds the plan from the last committed generation's survivors
  test::expect_resumed_calls_agree(make, 1, [&](const SerialRun& first) {
    return make_agents_plan(agents_def(cfg), AgentsSpec{}, survivors(test::written(first), gen_name("agents", 0)));
  });
}

}  // namespace
}  // namespace divcoll::stages
