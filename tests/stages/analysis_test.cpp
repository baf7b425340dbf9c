// the analysis stage's plans (stages/analysis.hpp) through the serial farm, on a deployment run through it first
#include "stages/analysis.hpp"

#include <gtest/gtest.h>

#include "collective/deploy_variants.hpp"
#include "morph/body.hpp"
#include "stages/deploy.hpp"
#include "stages/stage_testing.hpp"

namespace divcoll::stages {
namespace {

// a deployment of weak_uniform and weak_diverse connectors in two environments, and what the analyses read of it
struct Case {
  config::RunConfig cfg = test::tiny({"deploy.environments=flat,ice", "deploy.episode_steps=60", "deploy.pairs=3",
                                  "deploy.hidden_subsample=60", "connectors.kinds=weak_uniform,weak_diverse",
                                  "connectors.replicates=2", "analysis.max_states=40",
                                  "analysis.bootstrap_resamples=100"});
  std::vector<morph::Agent> agents = test::random_population(4);
  std::array<std::vector<std::vector<double>>, 2> weights;  // [type] per replicate
  test::Datasets deployed;
  Case() {
    DeployTypes t;
    for (int k = 0; k < 2; ++k) {
      for (uint64_t r = 0; r < 2; ++r) {
        Rng rng = make_rng(12, k, r);
        weights[k].push_back(morph::init_connector_params(rng, morph::kConnectorInitGains[2]));
      }
      const std::string kind = cfg.connectors.kinds[k];
      for (const char* dep : {"uniform", "diverse"}) {
        t.names.push_back(kind + "@" + dep);
        t.weights.push_back(weights[k]);
        t.tethers.push_back(collective::tether(cfg.connectors, kind));
        t.diverse.push_back(std::string(dep) == "diverse");
      }
    }
    const auto deploy = make_deploy_plan(deploy_def(cfg), agents, t);
    deployed = test::written(run_serial(*deploy));
  }
  std::unique_ptr<Plan> adversity(bool damaged = false) const {
    std::array<std::vector<std::pair<int, int>>, 2> pairs;
    pairs[0] = collective::deploy_uniform_pairs(cfg.deploy, cfg.connectors);
    const std::vector<double>& dp = test::at(deployed, "deploy/diverse_pairs").values;
    for (int q = 0; q < 3; ++q) pairs[1].emplace_back(static_cast<int>(dp[2 * q]), static_cast<int>(dp[2 * q + 1]));
    Deployed d;
    d.alone = test::at(deployed, "deploy/agents/travel_u").values;
    d.pairs = test::at(deployed, "deploy/collectives/travel_u").values;
    for (double s : test::at(deployed, "deploy/agents/status").values) d.alone_status.push_back(static_cast<uint8_t>(s));
    for (double s : test::at(deployed, "deploy/collectives/status").values) d.pairs_status.push_back(static_cast<uint8_t>(s));
    if (damaged) d.pairs[5] += 1;
    // weak_uniform@uniform is deploy's type 0, weak_diverse@diverse its type 3
    return make_adversity_plan(analysis_def(cfg), agents, weights, pairs, {0, 3}, 4, {"ice"}, std::move(d));
  }
  std::unique_ptr<Plan> familiarity() const { return familiarity(cfg); }
  std::unique_ptr<Plan> familiarity(const config::RunConfig& with) const {
    std::array<std::vector<float>, 2> hidden;
    for (int t = 0; t < 2; ++t)
      for (double v : test::at(deployed, "deploy/hidden/" + kAnalysisTypes[t] + "/states").values)
        hidden[t].push_back(static_cast<float>(v));
    const int K = static_cast<int>(test::at(deployed, "deploy/hidden/" + kAnalysisTypes[0] + "/states").dims[3]);
    return make_familiarity_plan(analysis_def(with), {"ice"}, std::move(hidden), K, 32);
  }
};

int64_t mismatches(const SerialRun& run) {
  for (const auto& [name, value] : run.state_attributes)
    if (name == "adversity/deploy_mismatches") return value;
  return -1;
}

TEST(AdversityPlan, ReSimulatesDeploysEpisodesExactlyAndRecordsTheDtwAndItsStatistics) {
  const Case c;
  const auto plan = c.adversity();
  EXPECT_EQ(plan->info().passes, 2);
  const SerialRun run = run_serial(*plan);
  EXPECT_EQ(mismatches(run), 0);  // every alone and pair episode gave deploy's travel, bit for bit
  EXPECT_EQ(run.items, 2 * (4 + 2 * 2 * 3));  // per environment: agents alone, then the two types' pairs
  const test::Datasets d = test::written(run);
  for (const std::string& t : kAnalysisTypes) {
    EXPECT_EQ(test::at(d, "analysis/adversity/" + t + "/dtw").dims, (std::vector<uint64_t>{2, 2, 3, 2}));
    EXPECT_EQ(test::at(d, "analysis/adversity/" + t + "/worse_slot").dims, (std::vector<uint64_t>{2, 2, 3}));
  }
  // clones tie alone: the posterior agent (slot 0) is the worse one
  for (double w : test::at(d, "analysis/adversity/weak_uniform@uniform/worse_slot").values) EXPECT_EQ(w, 0);
  EXPECT_EQ(test::at(d, "analysis/adversity/replicate_means").dims, (std::vector<uint64_t>{2, 2, 2}));
  EXPECT_EQ(test::at(d, "analysis/adversity/summary").dims, (std::vector<uint64_t>{2, 2, 3}));
  EXPECT_EQ(test::at(d, "analysis/adversity/welch").dims, (std::vector<uint64_t>{2, 3}));
  // a deploy result that differs is counted
  EXPECT_EQ(mismatches(run_serial(*c.adversity(true))), 1);
}

TEST(AdversityPlan, AResumeAfterAnEnvironmentGivesTheSameRowsAndStatistics) {
  const Case c;
  const test::Datasets want = test::written(run_serial(*c.adversity()));
  test::expect_same(test::resumed([&] { return c.adversity(); }, 1), want);
  const auto master = c.adversity(), worker = c.adversity();
  SerialOptions o;
  o.order = SerialOptions::Order::reversed;
  test::expect_same(test::written(run_serial(*master, o, worker.get())), want);
}

TEST(FamiliarityPlan, FitsEachNovelEnvironmentAgainstFlatAndTabulatesTheCells) {
  const Case c;
  const SerialRun run = run_serial(*c.familiarity());
  EXPECT_EQ(run.items, 2 * 2);  // one fit per type and replicate
  const test::Datasets d = test::written(run);
  for (const std::string& t : kAnalysisTypes) {
    const Dataset& counts = test::at(d, "analysis/familiarity/" + t + "/counts");
    const Dataset& n = test::at(d, "analysis/familiarity/" + t + "/n_states");
    EXPECT_EQ(counts.dims, (std::vector<uint64_t>{1, 2, 6}));
    EXPECT_EQ(n.dims, (std::vector<uint64_t>{1, 2, 2}));
    EXPECT_EQ(test::at(d, "analysis/familiarity/" + t + "/embedding").dims, (std::vector<uint64_t>{1, 2, 80, 2}));
    for (int r = 0; r < 2; ++r) {
      EXPECT_LE(n.values[2 * r], 40);  // at most analysis.max_states of each environment
      // every state of the fit is in exactly one kind of cell
      EXPECT_EQ(counts.values[6 * r] + counts.values[6 * r + 1] + counts.values[6 * r + 2], n.values[2 * r] + n.values[2 * r + 1]);
    }
  }
  EXPECT_EQ(test::at(d, "analysis/familiarity/table").dims, (std::vector<uint64_t>{1, 3, 3}));
  const auto worker = c.familiarity(), master = c.familiarity();
  SerialOptions o;
  o.order = SerialOptions::Order::reversed;
  test::expect_same(test::written(run_serial(*master, o, worker.get())), d);
}

// analysis.calibrated_cell_scale counts the same fits' states again at a second scale: what a run at that
// cell_scale counts, while the unit-scale counts stay as they were; with 0 there is no second dataset
TEST(FamiliarityPlan, TheCalibratedScaleCountsTheSameFitsAsThatCellScaleWould) {
  const Case c;
  const test::Datasets unit = test::written(run_serial(*c.familiarity()));
  config::RunConfig both = c.cfg, fine = c.cfg;
  both.analysis.calibrated_cell_scale = 3.0;
  fine.analysis.cell_scale = 3.0;
  const test::Datasets d = test::written(run_serial(*c.familiarity(both)));
  const test::Datasets at3 = test::written(run_serial(*c.familiarity(fine)));
  bool differs = false;
  for (const std::string& t : kAnalysisTypes) {
    const std::string g = "analysis/familiarity/" + t;
    EXPECT_EQ(unit.count(g + "/counts_calibrated"), 0u);
    EXPECT_EQ(test::at(d, g + "/counts").values, test::at(unit, g + "/counts").values);
    EXPECT_EQ(test::at(d, g + "/embedding").values, test::at(at3, g + "/embedding").values);
    EXPECT_EQ(test::at(d, g + "/counts_calibrated").dims, test::at(at3, g + "/counts").dims);
    EXPECT_EQ(test::at(d, g + "/counts_calibrated").values, test::at(at3, g + "/counts").values);
    differs = differs || test::at(at3, g + "/counts").values != test::at(unit, g + "/counts").values;
  }
  EXPECT_TRUE(differs);  // finer cells count differently here, so the comparison above could fail
}

TEST(AnalysisPlans, TheDriverAndTheSerialFarmMakeTheSameFarmCalls) {
  const Case c;
  auto adversity = [&] { return c.adversity(); };
  test::expect_driver_and_serial_calls_agree(adversity);
  test::expect_resumed_calls_agree(adversity, 1);
  test::expect_driver_and_serial_calls_agree([&] { return c.familiarity(); });
}

}  // namespace
}  // namespace divcoll::stages
