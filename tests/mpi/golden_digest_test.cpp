// the tiny preset's run file against a committed digest (tests/mpi/tiny_golden.txt): the cross-rank and
// kill-and-resume comparisons (run_determinism_test.sh) catch results that depend on how a run was made;
// this catches results that change while every rank count still agrees. It runs once per kernel path of the binary
// (nn/kernel_path.hpp, through DIVCOLL_KERNELS): every path this CPU can run must give the committed digest, and a path
// it cannot run is skipped, saying so
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>
#include <string>

#include "cli/commands.hpp"
#include "nn/kernel_path.hpp"
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

class TinyGolden : public ::testing::TestWithParam<std::string> {};

// a parameter is a kernel path, or "libc_without_fma": the fastest path with the C library's run-time choices made as
// on a CPU without AVX or FMA (glibc's GLIBC_TUNABLES), which picks other versions of sin, cos, exp, log and pow:
// divcoll's results must not depend on them (common/dmath.hpp). (The generic path with glibc's software fma, what
// such a CPU runs, gives the generic path's bits, about 25 times slower: too slow for the suite.)
TEST_P(TinyGolden, RunFileDatasetsHaveTheCommittedDigest) {
  namespace fs = std::filesystem;
  const bool old_cpu_libc = GetParam() == "libc_without_fma";
  const std::string kernels = old_cpu_libc ? nn::kernel_path_name(nn::best_kernel_path()) : GetParam();
  const nn::KernelPath path = nn::parse_kernel_path(kernels);
  bool built = false;
  for (nn::KernelPath p : nn::built_kernel_paths()) built = built || p == path;
  if (!built) GTEST_SKIP() << GetParam() << " is not a kernel path of this architecture";
  if (!nn::can_run(path)) GTEST_SKIP() << "this CPU (" << nn::cpu_description() << ") cannot run " << GetParam();
  const fs::path dir = fs::temp_directory_path() / ("divcoll_golden_" + GetParam() + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "tiny.h5").string();
  const std::string libc = old_cpu_libc ? "GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-FMA4,-AVX " : "";
  const std::string cmd = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + libc + "DIVCOLL_KERNELS=" +
                          kernels + " " + testing::divcoll_binary() + " run " + testing::source_dir() + "/configs/tiny.toml --out " +
                          out + " run.progress_every_s=0 > " + (dir / "log").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const std::string digest = cli::datasets_digest(out);
  const std::string golden_file = testing::source_dir() + "/tests/mpi/tiny_golden.txt";
  const std::string golden = golden_digest(golden_file);
  fs::remove_all(dir);
  EXPECT_EQ(digest, golden)
      << "the tiny preset's run-file datasets changed on kernel path " << GetParam() << " (digest " << digest
      << ", committed " << golden << ").\n"
      << "If you changed results on purpose, replace the digest line of " << golden_file << " with " << digest
      << " in the same commit and say why in its message. If not, find the change: make a run file with the\n"
      << "last good commit and `divcoll compare OLD.h5 NEW.h5` names the datasets that differ.";
}

INSTANTIATE_TEST_SUITE_P(KernelPath, TinyGolden, ::testing::Values("generic", "avx2", "avx512", "neon",
                                                                            "libc_without_fma"),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

TEST(KernelPathChoice, AnUnknownOrUnrunnablePathStopsTheProgramWithItsReason) {
  const std::string bin = testing::divcoll_binary();
  const std::string log = (std::filesystem::temp_directory_path() / ("divcoll_kp_" + std::to_string(::getpid()))).string();
  const int rc = std::system(("DIVCOLL_KERNELS=sse9 " + bin + " --version > " + log + " 2>&1").c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("DIVCOLL_KERNELS=sse9: unknown kernel path 'sse9'"), std::string::npos) << text;
  // the path in use is named by --version
  const int rc2 = std::system(("DIVCOLL_KERNELS=generic " + bin + " --version > " + log + " 2>&1").c_str());
  EXPECT_EQ(WEXITSTATUS(rc2), 0);
  std::ifstream in2(log);
  const std::string text2((std::istreambuf_iterator<char>(in2)), std::istreambuf_iterator<char>());
  EXPECT_NE(text2.find("kernels: generic on "), std::string::npos) << text2;
  std::filesystem::remove(log);
}

}  // namespace
}  // namespace divcoll
