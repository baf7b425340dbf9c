// the elementary functions that enter results (common/dmath.hpp): within 1 ulp of the C library's (itself within
// about half an ulp of the exact value) over the ranges divcoll uses and well beyond, their special values, and their
// bits on a fixed set of arguments against a committed digest, which every CPU and system must reproduce (the
// AArch64 engine build prints the same digest under qemu: tests/cross/aarch64_engine.sh)
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "common/dmath.hpp"
#include "common/dmath_grid.hpp"

namespace divcoll {
namespace {

int64_t ordered(double x) {
  int64_t i;
  std::memcpy(&i, &x, 8);
  return i < 0 ? std::numeric_limits<int64_t>::min() - i : i;
}
// distance in units in the last place (adjacent doubles are 1 apart)
int64_t ulps(double a, double b) { return std::abs(ordered(a) - ordered(b)); }

template <class F, class G>
int64_t worst_ulps(F ours, G libc, const std::vector<double>& xs) {
  int64_t worst = 0;
  for (double x : xs) worst = std::max(worst, ulps(ours(x), libc(x)));
  return worst;
}

std::vector<double> uniform(double lo, double hi, int n, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> v(n);
  for (double& x : v) x = u(g);
  return v;
}

TEST(Dmath, ExpAndLogWithinOneUlpOfTheCLibrary) {
  EXPECT_LE(worst_ulps(dmath::exp, [](double x) { return std::exp(x); }, uniform(-700, 700, 200000, 1)), 1);
  EXPECT_LE(worst_ulps(dmath::exp, [](double x) { return std::exp(x); }, uniform(-1, 1, 200000, 2)), 1);
  std::vector<double> pos = uniform(-690, 690, 200000, 3);
  for (double& x : pos) x = std::exp(x);
  EXPECT_LE(worst_ulps(dmath::log, [](double x) { return std::log(x); }, pos), 1);
  EXPECT_LE(worst_ulps(dmath::log, [](double x) { return std::log(x); }, uniform(0.5, 2, 200000, 4)), 1);
  EXPECT_LE(worst_ulps(dmath::log, [](double x) { return std::log(x); }, uniform(0x1p-53, 1, 200000, 5)), 1);
}

TEST(Dmath, SinAndCosWithinOneUlpOfTheCLibrary) {
  for (double range : {1.0, 10.0, 200.0, 1e4, 1e6}) {
    const std::vector<double> xs = uniform(-range, range, 200000, static_cast<uint64_t>(range));
    EXPECT_LE(worst_ulps(dmath::sin, [](double x) { return std::sin(x); }, xs), 1) << "|x| < " << range;
    EXPECT_LE(worst_ulps(dmath::cos, [](double x) { return std::cos(x); }, xs), 1) << "|x| < " << range;
  }
  // near multiples of π/2, where the reduction needs its second and third parts
  std::vector<double> near;
  for (int k = 1; k < 2000; ++k) {
    const double x = k * 1.5707963267948966;
    near.insert(near.end(), {x, std::nextafter(x, 0.0), std::nextafter(x, 1e9)});
  }
  EXPECT_LE(worst_ulps(dmath::sin, [](double x) { return std::sin(x); }, near), 1);
  EXPECT_LE(worst_ulps(dmath::cos, [](double x) { return std::cos(x); }, near), 1);
  // the agents' sine inputs: ω t Δt + 2π j / n for every step of a 3000-step episode
  std::vector<double> phases;
  for (int t = 0; t < 3000; ++t)
    for (int j = 0; j < 10; ++j) phases.push_back(10.0 * t * 0.004 + 2.0 * M_PI * j / 10);
  EXPECT_LE(worst_ulps(dmath::sin, [](double x) { return std::sin(x); }, phases), 1);
}

TEST(Dmath, PowIsExpOfYLogXToItsStatedAccuracy) {
  for (double b : {0.9, 0.999, 0.85, 0.05, 0.5, 2.0, 10.0})
    for (double t : {0.0, 1.0, 2.0, 3.5, 10.0, 100.0, 1000.0, 5000.0}) {
      const double want = std::pow(b, t);
      if (want < 1e-300 || want > 1e300) continue;
      // the rounding of y·log x, magnified by exp, and a few roundings more
      EXPECT_NEAR(dmath::pow(b, t) / want, 1.0, 2.3e-16 * (4 + 2 * std::abs(t * std::log(b)))) << b << "^" << t;
    }
  EXPECT_NEAR(dmath::pow(-2.0, 3.0), -8.0, 1e-14);
  EXPECT_NEAR(dmath::pow(-2.0, 2.0), 4.0, 1e-14);
  EXPECT_TRUE(std::isnan(dmath::pow(-2.0, 0.5)));
  EXPECT_EQ(dmath::pow(0.0, 2.0), 0.0);
  EXPECT_EQ(dmath::pow(0.0, -1.0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(dmath::pow(7.0, 0.0), 1.0);
  EXPECT_EQ(dmath::hypot(3.0, 4.0), 5.0);
}

TEST(Dmath, SpecialValues) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(dmath::exp(0.0), 1.0);
  EXPECT_EQ(dmath::exp(-inf), 0.0);
  EXPECT_EQ(dmath::exp(inf), inf);
  EXPECT_EQ(dmath::exp(710.0), inf);
  EXPECT_EQ(dmath::exp(-746.0), 0.0);
  EXPECT_TRUE(std::isnan(dmath::exp(nan)));
  EXPECT_EQ(dmath::log(1.0), 0.0);
  EXPECT_EQ(dmath::log(0.0), -inf);
  EXPECT_EQ(dmath::log(inf), inf);
  EXPECT_TRUE(std::isnan(dmath::log(-1.0)));
  EXPECT_EQ(dmath::log(4.9406564584124654e-324), std::log(4.9406564584124654e-324));
  EXPECT_EQ(dmath::sin(0.0), 0.0);
  EXPECT_EQ(dmath::cos(0.0), 1.0);
  EXPECT_TRUE(std::isnan(dmath::sin(inf)));
  EXPECT_TRUE(std::isnan(dmath::cos(nan)));
}

TEST(Dmath, BitsOnAFixedGridHaveTheCommittedDigest) {
  char got[32];
  std::snprintf(got, sizeof got, "%016llx", static_cast<unsigned long long>(test::dmath_grid_digest()));
  EXPECT_STREQ(got, "64b008fa45734a8e") << "dmath's bits changed: on purpose, put the new digest here";
}

}  // namespace
}  // namespace divcoll
