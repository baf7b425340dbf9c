// connector training's plans (stages/connectors.hpp) through the serial farm: a few pairs, iterations and steps
#include "stages/connectors.hpp"

#include <gtest/gtest.h>

#include "collective/deploy_variants.hpp"
#include "collective/pairs.hpp"
#include "collective/references.hpp"
#include "config/pipeline.hpp"
#include "evo/connector_opt.hpp"
#include "morph/body.hpp"
#include "stages/stage_testing.hpp"

namespace divcoll::stages {
namespace {

struct Case {
  config::RunConfig cfg;
  std::vector<morph::Agent> agents = test::random_population(4);
  std::vector<ConnectorSlot> slots;
  TrainSpec spec;
  explicit Case(std::vector<std::string> overrides) {
    overrides.insert(overrides.end(), {"connectors.kinds=weak_uniform,weak_diverse", "connectors.replicates=2",
                                       "connectors.iterations=3", "connectors.batch_pairs=3",
                                       "connectors.episode_steps=60"});
    cfg = test::tiny(overrides);
    const auto& C = cfg.connectors;
    const int R = C.replicates;
    // as the connectors stage's runner makes them: connector c = kind·R + replicate
    for (int k = 0; k < static_cast<int>(C.kinds.size()); ++k)
      for (int r = 0; r < R; ++r)
        slots.push_back({collective::tether(cfg.connectors, C.kinds[k]), C.kinds[k] == "weak_diverse", "flat",
                         kConnectorsStage + k * R + r, "connectors/" + C.kinds[k], r});
    spec = {"connectors", "connectors", C.iterations, C.batch_pairs, C.episode_steps};
  }
  std::unique_ptr<ConnectorsPlan> plan() const { return make_connectors_plan(connectors_def(cfg), agents, slots, spec); }
};

TEST(ConnectorsPlan, RecordsEveryIterationsCurvesTheWeightsAndTheState) {
  const Case c({});
  const auto plan = c.plan();
  const SerialRun run = run_serial(*plan);
  const uint64_t I = 3, R = 2, N = 4, Pc = sim::connector_param_count();
  EXPECT_EQ(run.done, 3);
  EXPECT_EQ(run.items, static_cast<int64_t>(I * N * 3));  // every slot's batch, every iteration
  const test::Datasets d = test::written(run);
  for (const char* kind : {"weak_uniform", "weak_diverse"}) {
    const std::string g = std::string("connectors/") + kind;
    for (const char* curve : {"/curve_u", "/curve_bl", "/nan_pairs"})
      EXPECT_EQ(test::at(d, g + curve).dims, (std::vector<uint64_t>{I, R})) << g << curve;
    EXPECT_EQ(test::at(d, g + "/params").dims, (std::vector<uint64_t>{R, Pc}));
    for (double v : test::at(d, g + "/curve_u").values) EXPECT_TRUE(std::isfinite(v)) << g;  // every row written, ok
  }
  for (const char* s : {"params", "adam_m", "adam_v"})
    EXPECT_EQ(test::at(d, std::string("connectors/state/") + s).dims, (std::vector<uint64_t>{N, Pc}));
  // the trained weights (what train_connectors broadcasts) are the recorded ones
  const auto w = plan->weights();
  ASSERT_EQ(w.size(), N);
  for (size_t q = 0; q < Pc; ++q) ASSERT_EQ(test::at(d, "connectors/weak_diverse/params").values[Pc + q], w[3][q]);
}

// connectors.network = joint: the plan trains the joint network's 3013 weights (its own random start, a step away
// from it after the iterations), records them in the same datasets, and resumes to the same run
TEST(ConnectorsPlan, TheJointNetworkTrainsItsOwnWeightsAndResumes) {
  const Case c({"connectors.network=\"joint\"", "run.stages=agents,connectors,deploy"});
  const SerialRun run = run_serial(*c.plan());
  const test::Datasets d = test::written(run);
  const uint64_t R = 2, Pj = sim::connector_param_count(true);
  for (const char* kind : {"weak_uniform", "weak_diverse"}) {
    const std::string g = std::string("connectors/") + kind;
    EXPECT_EQ(test::at(d, g + "/params").dims, (std::vector<uint64_t>{R, Pj})) << kind;
    for (double v : test::at(d, g + "/curve_u").values) EXPECT_TRUE(std::isfinite(v)) << g;
  }
  // replicate 0 of weak_uniform (connector 0) moved away from where it started
  Rng rng = make_rng(c.cfg.run.seed, c.slots[0].stream, config::kItemInitialWeights);
  const std::vector<double> start = collective::initial_connector_params(c.cfg.connectors, 0.6, rng);
  const auto& trained = test::at(d, "connectors/weak_uniform/params").values;
  ASSERT_EQ(start.size(), Pj);
  EXPECT_NE(std::vector<double>(trained.begin(), trained.begin() + Pj), start);
  test::expect_same(test::resumed([&] { return c.plan(); }, 2), d);
}

TEST(ConnectorsPlan, TheFirstIterationsCurveIsTheMeanOfItsPairEpisodes) {
  const Case c({});
  const auto plan = c.plan();
  const test::Datasets d = test::written(run_serial(*plan));
  sim::Simulator sim;
  sim::RunOptions ro;
  ro.steps = c.spec.episode_steps;
  ro.grad = true;
  ro.agent_param_grad = false;
  for (int s = 0; s < 4; ++s) {
    const ConnectorSlot& slot = c.slots[s];
    Rng init = make_rng(c.cfg.run.seed, slot.stream, config::kItemInitialWeights);
    const std::vector<double> w = morph::init_connector_params(init, c.cfg.connectors.init_out_gain);
    Rng batch = make_rng(c.cfg.run.seed, slot.stream, 0);
    const auto pairs = slot.diverse ? collective::random_pairs(batch, 4, c.spec.batch_pairs)
                                    : collective::uniform_pairs(c.spec.batch_pairs);
    evo::ProbeSum sum;
    for (const auto& [a, b] : pairs)
      sum.add(collective::run_pair(sim, c.agents[a], c.agents[b], w, slot.tether, "flat", sim::ContactLaw::coulomb, ro, nullptr));
    const double want = sum.mean().travel_u;
    EXPECT_EQ(test::at(d, slot.group + "/curve_u").values[slot.column], want) << slot.group << " " << slot.column;
  }
}

TEST(ConnectorsPlan, AWorkersPlanAndAnyComputeOrderGiveTheSameWeights) {
  const Case c({});
  const test::Datasets want = test::written(run_serial(*c.plan()));
  const auto again = c.plan();
  test::expect_same(test::written(run_serial(*again)), want);  // deterministic
  const auto master = c.plan(), worker = c.plan();
  SerialOptions o;
  o.order = SerialOptions::Order::shuffled;
  o.shuffle_seed = 5;
  test::expect_same(test::written(run_serial(*master, o, worker.get())), want);
}

TEST(ConnectorsPlan, AResumeFromACommittedIterationContinuesAsAnUninterruptedRun) {
  const Case c({});
  const test::Datasets want = test::written(run_serial(*c.plan()));
  for (int cut = 1; cut < 3; ++cut) test::expect_same(test::resumed([&] { return c.plan(); }, cut), want);
}

TEST(ConnectorsPlan, TheExtendedPlanKeepsTheBestWeightsAndResumesToTheSameRun) {
  const Case c({"connectors.keep_best=true", "connectors.validation_pairs=2", "connectors.lr_schedule=cosine"});
  ASSERT_TRUE(evo::extended(evo::opt_settings(c.cfg.connectors)));
  const auto plan = c.plan();
  EXPECT_TRUE(plan->closing_round());
  const SerialRun run = run_serial(*plan);
  const test::Datasets want = test::written(run);
  EXPECT_EQ(test::at(want, "connectors/weak_uniform/val_bl").dims, (std::vector<uint64_t>{4, 2}));  // I + 1 rows
  EXPECT_EQ(test::at(want, "connectors/weak_uniform/best_iteration").dims, std::vector<uint64_t>{2});
  for (double v : test::at(want, "connectors/weak_uniform/val_bl").values) EXPECT_FALSE(std::isnan(v));
  EXPECT_EQ(test::at(want, "connectors/state/best").dims, (std::vector<uint64_t>{4, 2}));
  // the kept weights are those of the best validation row
  for (int r = 0; r < 2; ++r) {
    const int best = static_cast<int>(test::at(want, "connectors/weak_uniform/best_iteration").values[r]);
    double top = -INFINITY;
    for (int it = 0; it <= 3; ++it) top = std::max(top, test::at(want, "connectors/weak_uniform/val_bl").values[it * 2 + r]);
    EXPECT_EQ(test::at(want, "connectors/weak_uniform/val_bl").values[best * 2 + r], top);
  }
  for (int cut = 1; cut < 3; ++cut) test::expect_same(test::resumed([&] { return c.plan(); }, cut), want);
}


TEST(ConnectorsPlan, AHorizonCurriculumTrainsOnShorterEpisodesAndValidatesOnTheFullOne) {
  const std::vector<std::string> extended = {"connectors.keep_best=true", "connectors.validation_pairs=2"};
  const test::Datasets want = test::written(run_serial(*Case(extended).plan()));
  // a curriculum that starts at the full length is no curriculum: the same run, bit for bit
  std::vector<std::string> full = extended;
  full.insert(full.end(), {"connectors.horizon_start=60", "connectors.horizon_ramp=2"});
  test::expect_same(test::written(run_serial(*Case(full).plan())), want);
  // from 20 steps: the first iteration's batch runs 20-step episodes (its curve is theirs), the validation 60
  std::vector<std::string> ramp = extended;
  ramp.insert(ramp.end(), {"connectors.horizon_start=20", "connectors.horizon_ramp=2"});
  const Case c(ramp);
  const test::Datasets d = test::written(run_serial(*c.plan()));
  sim::Simulator sim;
  sim::RunOptions ro;
  ro.grad = true;
  ro.agent_param_grad = false;
  const ConnectorSlot& slot = c.slots[0];  // weak_uniform, replicate 0: the clone pairs of agents 0, 1, 2
  Rng init = make_rng(c.cfg.run.seed, slot.stream, config::kItemInitialWeights);
  const std::vector<double> w = collective::initial_connector_params(c.cfg.connectors, slot.tether.amplitude, init);
  double at[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    ro.steps = k == 0 ? 20 : 60;
    evo::ProbeSum sum;
    for (const auto& [a, b] : collective::uniform_pairs(c.spec.batch_pairs))
      sum.add(collective::run_pair(sim, c.agents[a], c.agents[b], w, slot.tether, "flat", sim::ContactLaw::coulomb, ro, nullptr));
    at[k] = sum.mean().travel_u;
  }
  EXPECT_EQ(test::at(d, slot.group + "/curve_u").values[slot.column], at[0]);
  EXPECT_NE(at[0], at[1]);
  EXPECT_NE(test::at(d, slot.group + "/curve_u").values, test::at(want, slot.group + "/curve_u").values);
}

TEST(ConnectorsPlan, TheDriverAndTheSerialFarmMakeTheSameFarmCalls) {
  // the plain plan, the extended one (keep-best: a closing round) and the evolution strategy
  for (const std::vector<std::string>& keys :
       {std::vector<std::string>{}, {"connectors.keep_best=true", "connectors.validation_pairs=2"},
        {"connectors.optimizer=es"}}) {
    SCOPED_TRACE(keys.empty() ? std::string("plain") : keys[0]);
    const Case c(keys);
    auto make = [&] { return c.plan(); };
    test::expect_driver_and_serial_calls_agree(make);
    test::expect_resumed_calls_agree(make, 1);
  }
}

}  // namespace
}  // namespace divcoll::stages
