// the study folder (src/study/folder.hpp): the manifest written and read back, merged with another job's, and a
// folder continued only with the study it holds
#include "study/folder.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/check.hpp"
#include "testing.hpp"

namespace divcoll::study {
namespace {

namespace fs = std::filesystem;

struct StudyFolder : ::testing::Test {
  fs::path dir;
  std::string study_file;
  void SetUp() override {
    dir = fs::temp_directory_path() / ("divcoll_study_folder_" + std::to_string(getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    study_file = (dir / "study_file.toml").string();
    write_study("deploy.episode_steps=300");
  }
  void TearDown() override { fs::remove_all(dir); }
  void write_study(const std::string& set, const std::string& seeds = "[1, 2]") {
    std::ofstream(study_file) << "[study]\nname = \"f\"\nbase = \"" << testing::source_dir()
                              << "/configs/tiny.toml\"\nseeds = " << seeds
                              << "\nscale = ['run.stages=[\"agents\",\"connectors\",\"deploy\",\"analysis\"]']\n"
                              << "[[variant]]\nname = \"baseline\"\n[[variant]]\nname = \"long\"\nset = [\"" << set
                              << "\"]\n";
  }
  std::string out() const { return (dir / "out").string(); }
  // the study started: its folder and manifest, as `divcoll study` writes them before the first run
  Prepared start() {
    Prepared p = prepare(study_file, out(), false, false);
    create_folder(out(), p.s);
    save_manifest(out(), p.s, p.runs, p.st);
    return p;
  }
  std::string refusal(bool continuing) {
    try {
      prepare(study_file, out(), continuing, false);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(accepted)";
  }
};

TEST_F(StudyFolder, TheManifestReadsBackWhatWasWritten) {
  Prepared p = start();
  EXPECT_EQ(p.s.base, out() + "/" + kBaseCopy);
  EXPECT_TRUE(fs::is_regular_file(p.s.base));
  p.st[1].status = "complete", p.st[1].wall = 2.5, p.st[1].adopted_from = "/x/long/seed1.h5", p.st[1].commit = "abc";
  save_manifest(out(), p.s, p.runs, p.st);
  const Manifest m = read_manifest(out());
  EXPECT_EQ(m.name, "f");
  EXPECT_EQ(m.base_copy, kBaseCopy);
  ASSERT_EQ(m.runs.size(), 4u);
  const ManifestRun& r = m.runs[1];
  EXPECT_EQ(r.path, "long/seed1.h5");
  EXPECT_EQ(r.variant, "long");
  EXPECT_EQ(r.seed, 1u);
  EXPECT_EQ(r.from, "deploy");
  EXPECT_EQ(r.reuses, "baseline/seed1.h5");
  EXPECT_EQ(r.overrides, p.runs[1].overrides);
  EXPECT_EQ(r.st.status, "complete");
  EXPECT_EQ(r.st.wall, 2.5);
  EXPECT_EQ(r.st.adopted_from, "/x/long/seed1.h5");
  EXPECT_EQ(r.st.commit, "abc");
  EXPECT_EQ(m.runs[0].st.status, "planned");
  EXPECT_EQ(m.runs[0].reuses, "");
  // the text: the study file's own text kept, the reports' keys, and the status lines the job scripts grep
  const std::string text = manifest_text(p.s, p.runs, p.st);
  EXPECT_NE(text.find("format = 'divcoll-study'"), std::string::npos) << text;
  EXPECT_NE(text.find("status = 'complete'"), std::string::npos) << text;
  EXPECT_NE(text.find("[[run]]"), std::string::npos) << text;
  EXPECT_NE(text.find("[[variant]]"), std::string::npos) << text;
  EXPECT_EQ(text.find("added"), std::string::npos) << text;  // no variant joined late
  p.s.variants[1].added = "2026-12-06";
  EXPECT_NE(manifest_text(p.s, p.runs, p.st).find("added = '2026-12-06'"), std::string::npos);
}

TEST_F(StudyFolder, ARunAnotherJobCompletedStaysComplete) {
  Prepared p = start();
  std::vector<RunState> mine = p.st, theirs = p.st;
  theirs[2].status = "complete";
  save_manifest(out(), p.s, p.runs, theirs);
  // its run file is there: complete in the merge; a run marked complete whose file and summary are gone is not
  fs::create_directories(fs::path(out()) / "baseline");
  std::ofstream(fs::path(out()) / "baseline/seed2.h5") << "x";
  save_manifest(out(), p.s, p.runs, mine);
  EXPECT_EQ(mine[2].status, "complete");
  EXPECT_EQ(read_manifest(out()).runs[2].st.status, "complete");
}

TEST_F(StudyFolder, AFolderIsContinuedOnlyWithItsStudy) {
  start();
  EXPECT_EQ(refusal(false), out() + "/study.toml exists: pass --resume to continue the study, or give another --out");
  EXPECT_EQ(refusal(true), "(accepted)");
  // grown by a seed: accepted, the new runs planned
  write_study("deploy.episode_steps=300", "[1, 2, 3]");
  EXPECT_EQ(prepare(study_file, out(), true, false).runs.size(), 6u);
  // a held run whose config the study file changes is refused with its first differing key
  fs::create_directories(fs::path(out()) / "long");
  std::ofstream(fs::path(out()) / "long/seed1.h5") << "x";
  write_study("deploy.episode_steps=400");
  EXPECT_EQ(refusal(true), study_file + " changes the config of run long/seed1.h5, which " + out() +
                               " holds: deploy.episode_steps (300 -> 400). Only runs may be added to a study that has "
                               "started; give another --out to run the changed study");
  // a held run the study file no longer has
  write_study("deploy.episode_steps=300", "[2]");
  EXPECT_EQ(refusal(true), study_file + " has no run long/seed1.h5 (variant long, seed 1), which " + out() +
                               " holds: a study folder only grows; give another --out to run the changed study");
}

TEST_F(StudyFolder, AFolderWithoutManifestButWithRunsHoldsAnotherStudy) {
  fs::create_directories(fs::path(out()) / "baseline");
  std::ofstream(fs::path(out()) / "baseline/seed1.h5") << "x";
  EXPECT_EQ(refusal(false), out() + "/baseline/seed1.h5 exists but " + out() +
                                "/study.toml does not: this folder holds another study");
}

TEST_F(StudyFolder, ADamagedManifestIsSaid) {
  start();
  std::ofstream(fs::path(out()) / "study.toml") << "[run\n";
  try {
    read_manifest(out());
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(out() + "/study.toml is damaged: ", 0), 0u) << e.what();
    EXPECT_EQ(std::string(e.what()).find(" at line "), std::string::npos) << e.what();
  }
}

TEST(StudyFolderFiles, SummaryPathsAndTheKeysThatDoNotCount) {
  EXPECT_EQ(summary_path("d/v/seed3.h5"), fs::path("d/v/seed3.summary.json"));
  const config::RunConfig a = config::load_config(testing::source_dir() + "/configs/tiny.toml");
  EXPECT_EQ(first_difference(a, config::apply_overrides(a, {"run.progress_every_s=5", "output.dir=elsewhere"})), "");
  EXPECT_EQ(first_difference(a, config::apply_overrides(a, {"deploy.pairs=3"})), "deploy.pairs (4 -> 3)");
  EXPECT_FALSE(run_file_complete("/nowhere/seed1.h5"));
}

}  // namespace
}  // namespace divcoll::study
