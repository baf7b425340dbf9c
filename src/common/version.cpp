#include "common/version.hpp"

namespace divcoll {

const char* build_target() {
#if defined(DIVCOLL_BUILD_MARCH)
  return "-march=" DIVCOLL_BUILD_MARCH;
#elif defined(__x86_64__)
  return "x86-64 baseline";
#elif defined(__aarch64__)
  return "aarch64 baseline";
#else
  return "this architecture's baseline";
#endif
}

}  // namespace divcoll
