// the tiny preset's run file against a committed digest (tests/mpi/tiny_golden.txt): the cross-rank and
// kill-and-resume comparisons (run_determinism_test.sh) catch results that depend on how a run was made;
// this catches results that change while every rank count still agrees
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <string>

#include "cli/commands.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

std::string golden_digest(const std::string& file) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty() && line[0] != '#') return line.substr(0, line.find_first_of(" \t"));
  return "";
}

TEST(TinyGolden, RunFileDatasetsHaveTheCommittedDigest) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("divcoll_golden_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "tiny.h5").string();
  const std::string cmd = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + testing::divcoll_binary() + " run " + testing::source_dir() + "/configs/tiny.toml --out " +
                          out + " run.progress_every_s=0 > " + (dir / "log").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const std::string digest = cli::datasets_digest(out);
  const std::string golden_file = testing::source_dir() + "/tests/mpi/tiny_golden.txt";
  const std::string golden = golden_digest(golden_file);
  fs::remove_all(dir);
  EXPECT_EQ(digest, golden)
      << "the tiny preset's run-file datasets changed (digest " << digest << ", committed " << golden << ").\n"
      << "If you changed results on purpose, replace the digest line of " << golden_file << " with " << digest
      << " in the same commit and say why in its message. If not, find the change: make a run file with the\n"
      << "last good commit and `divcoll compare OLD.h5 NEW.h5` names the datasets that differ.";
}

}  // namespace
}  // namespace divcoll
