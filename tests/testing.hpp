// helpers shared by the tests: paths to shared test data and to the built binary
#pragma once

#include <string>

namespace divcoll::testing {
inline std::string shared_dir() { return DIVCOLL_SHARED_DIR; }
inline std::string parity_dir() { return std::string(DIVCOLL_SHARED_DIR) + "/testdata/parity"; }
inline std::string source_dir() { return DIVCOLL_SOURCE_DIR; }
inline std::string divcoll_binary() { return DIVCOLL_BINARY; }
}  // namespace divcoll::testing
