// helpers shared by the tests: paths to shared test data and to the built binary, test agents
#pragma once

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>

#include "collective/builders.hpp"

namespace divcoll::testing {
inline std::string shared_dir() { return DIVCOLL_SHARED_DIR; }
inline std::string parity_dir() { return std::string(DIVCOLL_SHARED_DIR) + "/testdata/parity"; }
inline std::string source_dir() { return DIVCOLL_SOURCE_DIR; }
inline std::string divcoll_binary() { return DIVCOLL_BINARY; }
// the text of README.md ("" if it cannot be read)
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
