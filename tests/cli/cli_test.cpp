// the divcoll executable: simulate writes what SPEC §9 says, bad input gives a message and a non-zero
// exit, and nothing that exists is overwritten without --force
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include "io/scene_file.hpp"
#include "io/trajectory_file.hpp"
#include "io/h5.hpp"
#include "sim/engine.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

namespace fs = std::filesystem;

struct Exec {
  int code;
  std::string out;  // stdout and stderr
};

Exec run(const std::string& args) {
  const std::string cmd = testing::divcoll_binary() + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[512];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  const int status = p ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("divcoll_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(Cli, SimulateWritesTrajectoryAndGradientsEqualToTheLibrary) {
  const std::string scene = testing::parity_dir() + "/scene1_step_up.h5";
  const Exec r = run("simulate --scene " + scene + " --steps 120 --out " + path("t.h5") + " --grad");
  ASSERT_EQ(r.code, 0) << r.out;
  const io::Trajectory t = io::read_trajectory(path("t.h5"));
  sim::RunOptions opt;
  opt.steps = 120;
  opt.grad = true;
  opt.record = true;
  const sim::RunResult want = sim::simulate(io::read_scene(scene), opt);
  EXPECT_EQ(t.steps, 120);
  EXPECT_EQ(t.x, want.x);
  EXPECT_EQ(t.v, want.v);
  EXPECT_EQ(t.touch, want.touch);
  EXPECT_EQ(t.travel, want.travel);
  EXPECT_EQ(t.status, "ok");
  EXPECT_EQ(t.grad_connector_params, want.grad_connector_params);
  EXPECT_EQ(t.grad_x0, want.grad_x0);
  // the same output again is refused, and the file is untouched
  const auto before = fs::last_write_time(path("t.h5"));
  const Exec again = run("simulate --scene " + scene + " --steps 10 --out " + path("t.h5"));
  EXPECT_NE(again.code, 0);
  EXPECT_NE(again.out.find("--force"), std::string::npos) << again.out;
  EXPECT_EQ(fs::last_write_time(path("t.h5")), before);
  EXPECT_EQ(io::read_trajectory(path("t.h5")).steps, 120);
}

TEST_F(Cli, BadInputIsRefusedWithAMessageAndNonZeroExit) {
  std::ofstream(path("text.h5")) << "not hdf5\n";
  struct Case {
    std::string args, expect;
  };
  const std::string good = testing::parity_dir() + "/scene0_flat.h5";
  const Case cases[] = {
      {"simulate --scene " + path("text.h5") + " --steps 10 --out " + path("o.h5"), "not an HDF5 file"},
      {"simulate --scene " + path("missing.h5") + " --steps 10 --out " + path("o.h5"), "missing.h5"},
      {"simulate --scene " + good + " --steps 0 --out " + path("o.h5"), "--steps"},
      {"simulate --scene " + good + " --steps 10 --out " + path("nodir/o.h5"), "does not exist"},
      {"scene --kind pair --env moon --out " + path("s.h5"), "unknown environment 'moon'"},
      {"scene --kind chain --agents 1 --out " + path("s.h5"), "--agents"},
      {"scene --kind blob --out " + path("s.h5"), "--kind"},
      {"frobnicate", "unknown command 'frobnicate'"},
      // run configs: refused before any work, naming the key and the allowed range
      {"evolve " + testing::source_dir() + "/configs/tiny.toml agents.population=0 --out " + path("r.h5"),
       "agents.population"},
      {"evolve " + testing::source_dir() + "/configs/tiny.toml agents.populaton=5 --out " + path("r.h5"),
       "did you mean agents.population"},
      {"evolve " + testing::source_dir() + "/configs/tiny.toml agents.episode_steps=0 --out " + path("r.h5"),
       "agents.episode_steps"},
      {"run " + testing::source_dir() + "/configs/tiny.toml scaling.sizes=1,3 --out " + path("r.h5"), "scaling.sizes"},
      {"run " + testing::source_dir() + "/configs/tiny.toml connectors.batch_pairs=50 --out " + path("r.h5"),
       "agents.population"},
      {"run " + testing::source_dir() + "/configs/tiny.toml deploy.environments=flat,moon --out " + path("r.h5"),
       "moon"},
      {"evolve " + path("text.h5") + " --out " + path("r.h5"), "text.h5"},
  };
  // bad input exits 2 (an internal failure would exit 1, a crash 134)
  for (const Case& c : cases) {
    const Exec r = run(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << "\n" << r.out;
  }
  EXPECT_FALSE(fs::exists(path("o.h5")));
  EXPECT_FALSE(fs::exists(path("r.h5")));
  EXPECT_FALSE(fs::exists(path("s.h5")));
}

TEST_F(Cli, SceneCommandWritesAChainThatSimulates) {
  const Exec w = run("scene --kind chain --agents 5 --env obstacle --seed 3 --out " + path("c.h5"));
  ASSERT_EQ(w.code, 0) << w.out;
  const sim::Scene s = io::read_scene(path("c.h5"));
  EXPECT_EQ(s.n_agents(), 5);
  EXPECT_EQ(s.n_connectors(), 4);
  EXPECT_EQ(s.env.name, "obstacle");
  const Exec r = run("simulate --scene " + path("c.h5") + " --steps 50 --out " + path("t.h5"));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("status ok"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace divcoll

namespace divcoll {
namespace {

TEST_F(Cli, ExistingRunFileIsNeitherOverwrittenNorResumedWithAnotherConfig) {
  const std::string cfg = testing::source_dir() + "/configs/tiny.toml";
  const std::string env = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ";
  ASSERT_EQ(std::system((env + testing::divcoll_binary() + " evolve " + cfg + " --out " + path("r.h5") + " > /dev/null").c_str()), 0);
  const auto before = fs::last_write_time(path("r.h5"));
  const Exec again = run("evolve " + cfg + " --out " + path("r.h5"));
  EXPECT_EQ(again.code, 2) << again.out;
  EXPECT_NE(again.out.find("--resume"), std::string::npos) << again.out;
  const Exec other = run("evolve " + cfg + " agents.epochs=3 --out " + path("r.h5") + " --resume");
  EXPECT_NE(other.code, 0) << other.out;
  EXPECT_NE(other.out.find("agents.epochs"), std::string::npos) << other.out;
  EXPECT_EQ(fs::last_write_time(path("r.h5")), before);
  // the finished run resumes to itself
  const Exec same = run("evolve " + cfg + " --out " + path("r.h5") + " --resume");
  EXPECT_EQ(same.code, 0) << same.out;
  EXPECT_NE(same.out.find("already done"), std::string::npos) << same.out;
}

}  // namespace
}  // namespace divcoll
