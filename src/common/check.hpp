// error tiers (STYLE.md lesson 8)
//  - InputError: bad user input (config, scene file, CLI); caught in main, message + non-zero exit
//  - DIVCOLL_THROW_UNLESS(cond, msg): always on, throws InputError for caller mistakes
//  - DIVCOLL_DEMAND(cond): always on, aborts on a broken internal invariant
#pragma once

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

namespace divcoll {

// an input that the program refuses; what() is a complete sentence for the user
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

namespace detail {
[[noreturn]] inline void demand_failed(const char* cond, const char* file, int line) {
  std::fprintf(stderr, "divcoll: internal error: %s failed at %s:%d\n", cond, file, line);
  std::abort();
}
}  // namespace detail

// builds a message from stream pieces: throw InputError(msg() << "key " << k << " ...")
struct msg {
  std::ostringstream os;
  template <class T>
  msg& operator<<(const T& v) {
    os << v;
    return *this;
  }
  operator std::string() const { return os.str(); }
};

}  // namespace divcoll

#define DIVCOLL_THROW_UNLESS(cond, message)                    \
  do {                                                         \
    if (!(cond)) throw ::divcoll::InputError(::divcoll::msg() << message); \
  } while (0)

#define DIVCOLL_DEMAND(cond)                                                    \
  do {                                                                          \
    if (!(cond)) ::divcoll::detail::demand_failed(#cond, __FILE__, __LINE__); \
  } while (0)
