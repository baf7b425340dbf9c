// FNV-1a of the bits of common/dmath's functions on a fixed grid of arguments: a computation that differs anywhere
// (another compiler's contraction, a CPU's rounding) changes it. Checked against a committed digest by
// tests/common/dmath_test.cpp and printed by tests/sim/engine_probe.cpp on every architecture it is built for.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "common/dmath.hpp"

namespace divcoll::test {

inline uint64_t dmath_grid_digest() {
  uint64_t h = 14695981039346656037ull;
  auto feed = [&](double v) {
    unsigned char b[8];
    std::memcpy(b, &v, 8);
    for (unsigned char c : b) h = (h ^ c) * 1099511628211ull;
  };
  for (int i = -2000; i <= 2000; ++i) {
    const double x = i * 0.37;
    feed(dmath::exp(x * 0.5)), feed(dmath::log(std::abs(x) + 1e-3)), feed(dmath::sin(x)), feed(dmath::cos(x));
    feed(dmath::pow(0.999, std::abs(x))), feed(dmath::hypot(x, 1.5));
  }
  return h;
}

}  // namespace divcoll::test
