// the runs of a study (src/study/plan.hpp): seed by seed, each seed's variants in file order, and the earlier run of
// its seed whose stages each reuses (the one that shares the most leading stages with the same keys)
#include "study/plan.hpp"

#include <gtest/gtest.h>

#include <string>

#include "common/check.hpp"
#include "testing.hpp"

namespace divcoll::study {
namespace {

// the tiny preset's agents, connectors, deploy and analysis, with `variants` (name, set) at seeds 1 and 2
Study tiny_study(const std::vector<std::pair<std::string, std::vector<std::string>>>& variants) {
  Study s;
  s.name = "t";
  s.base = s.base_given = testing::source_dir() + "/configs/tiny.toml";
  s.seeds = {1, 2};
  s.scale = {"run.stages=[\"agents\",\"connectors\",\"deploy\",\"analysis\"]",
             "connectors.kinds=[\"weak_uniform\",\"weak_diverse\"]"};
  for (const auto& [name, set] : variants) s.variants.push_back({name, "", set, {}, ""});
  return s;
}

std::string computes(const PlannedRun& r) { return stages_text(computed(r)); }

TEST(StudyPlan, RunsSeedBySeedAndReusesTheStagesWhoseKeysAgree) {
  const auto runs = plan(tiny_study({{"baseline", {}}, {"long_deploy", {"deploy.episode_steps=300"}}}));
  ASSERT_EQ(runs.size(), 4u);
  const char* paths[] = {"baseline/seed1.h5", "long_deploy/seed1.h5", "baseline/seed2.h5", "long_deploy/seed2.h5"};
  for (int i = 0; i < 4; ++i) EXPECT_EQ(runs[i].path, paths[i]);
  EXPECT_EQ(runs[1].seed, 1u);
  EXPECT_EQ(runs[1].cfg.run.seed, 1u);
  EXPECT_EQ(runs[1].cfg.deploy.episode_steps, 300);
  EXPECT_EQ(runs[1].overrides.back(), "run.seed=1");
  // a baseline computes everything; the variant takes agents and connectors from its seed's baseline
  EXPECT_EQ(runs[0].base_run, -1);
  EXPECT_EQ(computes(runs[0]), "agents,connectors,deploy,analysis");
  EXPECT_EQ(runs[1].base_run, 0);
  EXPECT_EQ(runs[1].from, "deploy");
  EXPECT_EQ(computes(runs[1]), "deploy,analysis");
  EXPECT_EQ(runs[3].base_run, 2);  // never a run of another seed
}

TEST(StudyPlan, ReusesNothingAcrossAnAgentsKeyOrTheRunsPrecision) {
  for (const char* key : {"agents.epochs=1", "run.precision=float_networks", "run.contact=no_slip"}) {
    const auto runs = plan(tiny_study({{"baseline", {}}, {"other", {key}}}));
    EXPECT_EQ(runs[1].base_run, -1) << key;
    EXPECT_EQ(computes(runs[1]), "agents,connectors,deploy,analysis") << key;
  }
  const auto runs = plan(tiny_study({{"baseline", {}}, {"weak", {"connectors.weak_stiffness=1000"}}}));
  EXPECT_EQ(runs[1].from, "connectors");
}

TEST(StudyPlan, ASameConfigRecomputesItsLastStageOnACopy) {
  const auto runs = plan(tiny_study({{"baseline", {}}, {"again", {}}}));
  EXPECT_EQ(runs[1].base_run, 0);
  EXPECT_EQ(runs[1].from, "analysis");
  EXPECT_EQ(computes(runs[1]), "analysis");
}

TEST(StudyPlan, AnAnalysisKeyReusesDeployAndTheBaseWithMostSharedStagesWins) {
  const auto runs = plan(tiny_study({{"baseline", {}},
                                     {"long_deploy", {"deploy.episode_steps=300"}},
                                     {"long_deploy_dtw", {"deploy.episode_steps=300", "analysis.dtw_every=5"}}}));
  EXPECT_EQ(runs[2].base_run, 1);
  EXPECT_EQ(runs[2].from, "analysis");
}

TEST(StudyPlan, AVariantRunsOnlyAtItsSeeds) {
  Study s = tiny_study({{"baseline", {}}, {"extra", {"deploy.episode_steps=300"}}});
  s.variants[1].seeds = {2};
  const auto runs = plan(s);
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(runs[2].path, "extra/seed2.h5");
  EXPECT_EQ(runs[2].base_run, 1);
}

TEST(StudyPlan, ABadOverrideNamesTheVariantAndSeed) {
  try {
    plan(tiny_study({{"baseline", {}}, {"bad", {"deploy.episode_stepz=300"}}}));
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("variant bad (seed 1): unknown key deploy.episode_stepz", 0), 0u) << e.what();
  }
}

TEST(StudyPlan, FindsARunByNumberOrPath) {
  const auto runs = plan(tiny_study({{"baseline", {}}, {"long_deploy", {"deploy.episode_steps=300"}}}));
  EXPECT_EQ(find_run(runs, "1"), 0);
  EXPECT_EQ(find_run(runs, "4"), 3);
  EXPECT_EQ(find_run(runs, "long_deploy/seed1.h5"), 1);
  EXPECT_EQ(find_run(runs, "baseline/seed2"), 2);
  EXPECT_THROW(find_run(runs, "5"), InputError);
  EXPECT_THROW(find_run(runs, "0"), InputError);
  try {
    find_run(runs, "nothing/seed1");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "--run nothing/seed1: no such run in the study (give its number or its path, e.g. "
                           "baseline/seed1.h5)");
  }
}

}  // namespace
}  // namespace divcoll::study
