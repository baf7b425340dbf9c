// helpers shared by the tests: paths to shared test data and to the built binary, test agents
#pragma once

#include <sys/wait.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "collective/builders.hpp"

namespace divcoll::testing {
// the project's shared folder (SPEC, parity scenes): the environment variable DIVCOLL_SHARED_DIR when set,
// else the CMake cache variable of the same name (default: ../shared beside the checkout)
inline std::string shared_dir() {
  const char* e = std::getenv("DIVCOLL_SHARED_DIR");
  return e && *e ? std::string(e) : std::string(DIVCOLL_SHARED_DIR);
}
inline std::string parity_dir() { return shared_dir() + "/testdata/parity"; }
inline std::string source_dir() { return DIVCOLL_SOURCE_DIR; }
inline std::string divcoll_binary() { return DIVCOLL_BINARY; }
// the text of README.md ("" if it cannot be read)
// runs the divcoll binary with args (a shell word list); its exit code and its stdout and stderr together
struct Exec {
  int code;
  std::string out;  // stdout and stderr
};
inline Exec run_divcoll(const std::string& args) {
  const std::string cmd = divcoll_binary() + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[512];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  const int status = p ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

inline std::string readme() {
  std::ifstream in(source_dir() + "/README.md");
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
// a random agent from stream (seed, `stream`) with anchors from a short (300-step) run on flat
inline collective::Agent agent_with_anchors(uint64_t seed, uint64_t stream) {
  Rng rng = make_rng(seed, stream, 0);
  collective::Agent a = collective::random_agent(rng);
  a.anchors = collective::compute_anchors(a, {}, 300);
  return a;
}
}  // namespace divcoll::testing
