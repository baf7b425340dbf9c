// divcoll grad-diag and connector-opt on the tiny preset's agents: at a short horizon and a small perturbation
// the backpropagated gradient is the slope of the batch objective (finite differences along it agree); bad
// flags are refused with exit 2; connector-opt writes its curves and summary
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include "testing.hpp"

namespace divcoll {
namespace {

namespace fs = std::filesystem;

class GradDiag : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("divcoll_grad_diag_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    run_ = (dir_ / "agents.h5").string();
    const auto r = testing::run_divcoll("run " + testing::source_dir() + "/configs/tiny.toml 'run.stages=[\"agents\"]' --out " + run_);
    ASSERT_EQ(r.code, 0) << r.out;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
  static std::string run_;
};
fs::path GradDiag::dir_;
std::string GradDiag::run_;

TEST_F(GradDiag, GradientIsTheSlopeAtAShortHorizonAndSmallScale) {
  const auto r = testing::run_divcoll("grad-diag " + run_ + " --pairs 3 --horizons 40,80 --scales 1e-7,1e-2 --directions 1 --window 20");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("## horizon 40 steps"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("## horizon 80 steps"), std::string::npos);
  EXPECT_NE(r.out.find("truncated backpropagation, window 20"), std::string::npos);
  // the ĝ and random rows of the 40-step table: FD/BPTT at scale 1e-7 is 1 to 3 digits
  std::istringstream in(r.out.substr(r.out.find("## horizon 40 steps"), r.out.find("## horizon 80 steps") -
                                                                                  r.out.find("## horizon 40 steps")));
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.rfind("| ĝ |", 0) != 0 && line.rfind("| random 1 |", 0) != 0) continue;
    // | dir | g·d | ratio@1e-7 | ratio@1e-2 | ...
    std::vector<std::string> cells;
    std::stringstream ls(line);
    std::string c;
    while (std::getline(ls, c, '|')) cells.push_back(c);
    ASSERT_GE(cells.size(), 5u) << line;
    EXPECT_NEAR(std::stod(cells[3]), 1.0, 1e-3) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 2) << r.out;
}

TEST_F(GradDiag, BadFlagsAreRefused) {
  for (const char* bad : {"--kind blob", "--horizons 0", "--scales -1", "--horizons x",
                           "connectors.lr=-1"}) {
    const auto r = testing::run_divcoll("grad-diag " + run_ + " " + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.out;
  }
}

TEST_F(GradDiag, ConnectorOptWritesCurvesAndSummary) {
  const std::string out = (dir_ / "opt").string();
  const auto r = testing::run_divcoll("connector-opt " + run_ +
                      " connectors.kinds=weak_uniform connectors.iterations=3 connectors.keep_best=true"
                      " connectors.validation_pairs=2 connectors.lr_schedule=cosine --eval-pairs 2"
                      " --eval-steps 50,100 --out " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream c(out + "_curves.csv"), s(out + "_summary.csv");
  std::string line;
  int n = 0;
  while (std::getline(c, line)) ++n;
  EXPECT_EQ(n, 1 + 4);  // header, 3 iterations + the final validation
  n = 0;
  while (std::getline(s, line)) ++n;
  EXPECT_EQ(n, 1 + 4);  // header, two episode lengths × (kept, last) weights
  // an existing output is not overwritten
  EXPECT_EQ(testing::run_divcoll("connector-opt " + run_ + " --out " + out).code, 2);
}

}  // namespace
}  // namespace divcoll
