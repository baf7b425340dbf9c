// common/aligned.hpp: a LineVector's storage starts on a cache line whatever was allocated before it and
// however it grew (the network kernels' speed depends on it, not their results: that is asserted by the
// parity and golden-digest tests).
#include "common/aligned.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

namespace divcoll {
namespace {

bool on_line(const void* p) { return reinterpret_cast<std::uintptr_t>(p) % kCacheLine == 0; }

TEST(LineVector, StartsOnACacheLineAfterAllocationsOfEverySize) {
  std::vector<std::unique_ptr<char[]>> before;
  int off_line_mallocs = 0;
  for (int n = 1; n <= 200; ++n) {
    before.emplace_back(new char[static_cast<size_t>(n) * 8]);  // the heap in a different state each time
    off_line_mallocs += !on_line(before.back().get());
    LineVector<double> d(static_cast<size_t>(n));
    LineVector<float> f(static_cast<size_t>(3 * n));
    ASSERT_TRUE(on_line(d.data())) << n;
    ASSERT_TRUE(on_line(f.data())) << n;
  }
  // the property is not one plain allocations have by luck (else this test would show nothing)
  EXPECT_GT(off_line_mallocs, 0);
}

TEST(LineVector, StaysOnACacheLineAsItGrowsAndIsCopied) {
  LineVector<double> v;
  for (int n = 0; n < 5000; ++n) {
    v.push_back(n);
    ASSERT_TRUE(on_line(v.data())) << v.size();
  }
  LineVector<double> w = v;
  EXPECT_TRUE(on_line(w.data()));
  EXPECT_EQ(w, v);
  w.assign(7, 1.5);
  EXPECT_TRUE(on_line(w.data()));
  EXPECT_EQ(w.size(), 7u);
}

}  // namespace
}  // namespace divcoll
