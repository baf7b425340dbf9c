// a study's runs in one session (src/study/runs.hpp run_study), with a session of one process whose runs write a
// run file that has ended: what each run is asked, the manifest after it, a resumed and a grown study, --run's wait
// for its base, a failed run; and --status over the folder
#include "study/runs.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/check.hpp"
#include "io/h5.hpp"
#include "study/folder.hpp"
#include "study/status.hpp"
#include "testing.hpp"

namespace divcoll::study {
namespace {

namespace fs = std::filesystem;

// one process; a run writes its run file with end_time and, for each stage it computes, a group with wall_s
struct OneProcess final : Session {
  std::vector<RunRequest> runs;
  int fail_run = -1;  // the run (its number among those asked) that fails with exit 1
  bool leader() const override { return true; }
  int share(int value) override { return value; }
  void wait_all() override {}
  void on_leader(const std::function<void()>& f) override { f(); }
  int run(const RunRequest& r) override {
    runs.push_back(r);
    if (static_cast<int>(runs.size()) - 1 == fail_run) return 1;
    fs::create_directories(fs::path(r.out).parent_path());
    io::h5::File f = io::h5::File::create(r.out, true);
    f.write_string("end_time", "now");
    for (const char* stage : {"agents", "connectors", "deploy", "analysis"})
      f.create_group(stage).write_double("wall_s", 1.0);
    f.close();
    return 0;
  }
};

struct StudyRuns : ::testing::Test {
  fs::path dir;
  void SetUp() override {
    dir = fs::temp_directory_path() / ("divcoll_study_runs_" + std::to_string(getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string out() const { return (dir / "out").string(); }
  // configs/studies/tiny.toml, whose base is given whole (2 variants x `seeds`)
  std::string study_file(const std::string& seeds = "[1, 2]") const {
    const std::string path = (dir / "tiny.toml").string();
    std::ofstream(path) << "[study]\nname = \"tiny\"\nbase = \"" << testing::source_dir()
                        << "/configs/tiny.toml\"\nseeds = " << seeds
                        << "\nscale = ['run.stages=[\"agents\",\"connectors\",\"deploy\",\"analysis\"]']\n"
                        << "[[variant]]\nname = \"baseline\"\n"
                        << "[[variant]]\nname = \"long_deploy\"\nset = [\"deploy.episode_steps=300\"]\n";
    return path;
  }
  int study(OneProcess& s, bool resume = false, const std::string& run = "", const std::string& seeds = "[1, 2]") {
    ::testing::internal::CaptureStdout();
    ::testing::internal::CaptureStderr();
    const int code = run_study({study_file(seeds), out(), resume, false, run}, s);
    said = ::testing::internal::GetCapturedStdout() + ::testing::internal::GetCapturedStderr();
    return code;
  }
  std::string said;
};

TEST_F(StudyRuns, EveryRunIsAskedForWithWhatItReuses) {
  OneProcess s;
  ASSERT_EQ(study(s), 0) << said;
  ASSERT_EQ(s.runs.size(), 4u);
  const std::string base_copy = out() + "/" + kBaseCopy;
  EXPECT_EQ(s.runs[0].out, out() + "/baseline/seed1.h5");
  EXPECT_EQ(s.runs[0].config, base_copy);
  EXPECT_TRUE(s.runs[0].resume);
  EXPECT_EQ(s.runs[0].from, "");
  EXPECT_EQ(s.runs[1].out, out() + "/long_deploy/seed1.h5");
  EXPECT_FALSE(s.runs[1].resume);
  EXPECT_EQ(s.runs[1].from, "deploy");
  EXPECT_EQ(s.runs[1].base, out() + "/baseline/seed1.h5");
  EXPECT_EQ(s.runs[1].overrides.back(), "run.seed=1");
  for (const ManifestRun& r : read_manifest(out()).runs) EXPECT_EQ(r.st.status, "complete") << r.path;
  EXPECT_NE(said.find("study: run 4/4 long_deploy seed 2 stages deploy,analysis (earlier stages from "
                      "baseline/seed2.h5) | elapsed"), std::string::npos) << said;
  EXPECT_NE(said.find("study tiny: done, 4 runs in " + out()), std::string::npos) << said;
}

TEST_F(StudyRuns, AResumedStudyRunsWhatIsLeftAndAGrownOneItsNewRuns) {
  OneProcess first;
  first.fail_run = 2;
  EXPECT_EQ(study(first), 1);
  EXPECT_EQ(read_manifest(out()).runs[2].st.status, "planned");
  OneProcess refused;
  EXPECT_EQ(study(refused), 2);
  EXPECT_NE(said.find("exists: pass --resume"), std::string::npos) << said;
  EXPECT_TRUE(refused.runs.empty());
  OneProcess again;
  ASSERT_EQ(study(again, true), 0) << said;
  ASSERT_EQ(again.runs.size(), 2u);
  EXPECT_EQ(again.runs[0].out, out() + "/baseline/seed2.h5");
  EXPECT_NE(said.find("study: run 1/4 baseline seed 1: complete in"), std::string::npos) << said;
  OneProcess grown;
  ASSERT_EQ(study(grown, true, "", "[1, 2, 3]"), 0) << said;
  ASSERT_EQ(grown.runs.size(), 2u);
  EXPECT_EQ(grown.runs[1].out, out() + "/long_deploy/seed3.h5");
  EXPECT_EQ(grown.runs[1].from, "deploy");
}

TEST_F(StudyRuns, ARunWaitsForItsBase) {
  OneProcess s;
  EXPECT_EQ(study(s, false, "2"), 2);
  EXPECT_NE(said.find("--run K computes one run of a study folder that exists: pass --resume too"), std::string::npos);
  EXPECT_FALSE(fs::exists(out()));
  EXPECT_EQ(study(s, true, "2"), kBaseNotComplete);
  EXPECT_TRUE(s.runs.empty());
  EXPECT_NE(said.find("run 2 (long_deploy/seed1.h5) reuses the stages before deploy of run baseline/seed1.h5, which "
                      "is not complete yet"), std::string::npos) << said;
  EXPECT_EQ(study(s, true, "baseline/seed1"), 0) << said;
  EXPECT_EQ(study(s, true, "2"), 0) << said;
  ASSERT_EQ(s.runs.size(), 2u);
  EXPECT_NE(said.find("study tiny: run 2 (long_deploy/seed1.h5) complete"), std::string::npos) << said;
}

TEST_F(StudyRuns, APlanWritesNothing) {
  OneProcess s;
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(run_study({study_file(), out(), false, true, ""}, s), 0);
  const std::string text = ::testing::internal::GetCapturedStdout();
  EXPECT_TRUE(s.runs.empty());
  EXPECT_FALSE(fs::exists(out()));
  EXPECT_NE(text.find("= 4 runs of"), std::string::npos) << text;
  EXPECT_NE(text.find("  2 long_deploy/seed1.h5: computes deploy,analysis, reuses baseline/seed1.h5"),
            std::string::npos) << text;
}

TEST_F(StudyRuns, TheStatusOfTheFolder) {
  OneProcess s;
  s.fail_run = 3;
  EXPECT_EQ(study(s), 1);
  std::ofstream(fs::path(out()) / "long_deploy/seed2.job") << "scheduler=slurm\njob=77\nstate=failed\nrc=1\n";
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(status(out()), 1);
  const std::string text = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(text.find("study tiny in " + out() + ": 4 runs"), std::string::npos) << text;
  EXPECT_NE(text.find("  1 baseline/seed1.h5: done"), std::string::npos) << text;
  EXPECT_NE(text.find("  4 long_deploy/seed2.h5: failed (job 77), status 1"), std::string::npos) << text;
  EXPECT_NE(text.find("3 done, 0 running, 0 to run, 0 waiting on their base, 1 failed"), std::string::npos) << text;
  EXPECT_THROW(status(dir.string()), InputError);
}

}  // namespace
}  // namespace divcoll::study
