// statistics against the values of ANALYSIS.md §4.3
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "analysis/stats.hpp"

namespace divcoll::analysis {
namespace {

std::vector<double> range(double from, double to) {
  std::vector<double> v;
  for (double x = from; x <= to; x += 1.0) v.push_back(x);
  return v;
}

const std::vector<double> kA{1.0, 1.2, 0.9, 1.1, 1.05, 0.95, 1.15, 0.85, 1.0, 1.1};
const std::vector<double> kB{1.3, 2.0, 1.1, 2.5, 1.6, 1.2, 2.2, 1.4, 1.9, 1.0};
const std::vector<double> kA2{2.1, 2.5, 1.9, 2.8, 2.2, 2.6, 2.4, 2.0, 2.3, 2.7};

TEST(Stats, WelchOnSeparatedRanges) {
  const TestResult r = welch_t_test(range(1, 10), range(11, 20));
  EXPECT_NEAR(r.statistic, -7.38549, 1e-5);
  EXPECT_NEAR(r.df, 18.0, 1e-9);
  EXPECT_NEAR(r.p, 7.503e-7, 1e-9);
}

TEST(Stats, WelchAndStudentAreToldApartWithUnequalVariances) {
  const TestResult w = welch_t_test(kA, kB);
  EXPECT_NEAR(w.statistic, -3.59284, 1e-5);
  EXPECT_NEAR(w.df, 9.8607, 1e-4);
  EXPECT_NEAR(w.p, 0.005017, 1e-6);
  const TestResult s = student_t_test(kA, kB);
  EXPECT_NEAR(s.p, 0.002080, 1e-6);
  EXPECT_NEAR(s.df, 18.0, 1e-12);
  // symmetric in the sign of t
  EXPECT_NEAR(welch_t_test(kB, kA).p, w.p, 1e-15);
}

TEST(Stats, MannWhitneyExactAndAsymptotic) {
  const TestResult exact = mann_whitney_u(range(1, 10), range(11, 20));
  EXPECT_EQ(exact.statistic, 0.0);
  EXPECT_NEAR(exact.p, 1.0825e-5, 1e-8);
  EXPECT_NEAR(exact.p, 2.0 / 184756.0, 1e-15);  // 2 / C(20, 10)
  // a tie forces the normal approximation with continuity correction
  std::vector<double> a = range(1, 10), b = range(11, 20);
  b[0] = 10.0;  // ties with a's largest: U = 0.5
  const TestResult approx = mann_whitney_u(a, b);
  EXPECT_EQ(approx.statistic, 0.5);
  EXPECT_GT(approx.p, 1.0e-4);
  EXPECT_LT(approx.p, 3.0e-4);
  EXPECT_NEAR(mann_whitney_u(b, a).p, approx.p, 1e-15);
}

TEST(Stats, SemUsesNMinusOne) {
  EXPECT_NEAR(mean(kA2), 2.35, 1e-12);
  EXPECT_NEAR(sample_sd(kA2), 0.302765, 1e-6);
  EXPECT_NEAR(sem(kA2), 0.0957427, 1e-7);
  EXPECT_TRUE(std::isnan(sem(std::vector<double>{1.0})));
  EXPECT_TRUE(std::isnan(mean(std::vector<double>{})));
}

TEST(Stats, BootstrapCiContainsTheMeanAndIsSeeded) {
  const Interval ci = bootstrap_ci(kA2, 42, 10000);
  EXPECT_LT(ci.lo, 2.35);
  EXPECT_GT(ci.hi, 2.35);
  EXPECT_GT(ci.lo, 2.35 - 0.25);
  EXPECT_LT(ci.hi, 2.35 + 0.25);
  EXPECT_NEAR(ci.lo, 2.18, 0.03);
  EXPECT_NEAR(ci.hi, 2.53, 0.03);
  const Interval again = bootstrap_ci(kA2, 42, 10000);
  EXPECT_EQ(ci.lo, again.lo);
  EXPECT_EQ(ci.hi, again.hi);
  // with few resamples the interval depends on the seed
  bool differs = false;
  const Interval few = bootstrap_ci(kA2, 42, 20);
  for (uint64_t seed = 43; seed < 53; ++seed) {
    const Interval other = bootstrap_ci(kA2, seed, 20);
    differs = differs || other.lo != few.lo || other.hi != few.hi;
  }
  EXPECT_TRUE(differs);
}

TEST(Stats, LinearQuantileIsNumpys) {
  const std::vector<double> s{1.0, 2.0, 4.0, 8.0};
  EXPECT_DOUBLE_EQ(quantile_linear(s, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(quantile_linear(s, 1.0), 8.0);
  EXPECT_DOUBLE_EQ(quantile_linear(s, 0.5), 3.0);    // position 1.5
  EXPECT_DOUBLE_EQ(quantile_linear(s, 0.25), 1.75);  // position 0.75
}

TEST(Stats, IncompleteBetaGivesTheTailOfStudentsT) {
  EXPECT_NEAR(t_two_sided_p(2.100922, 18.0), 0.05, 1e-6);
  EXPECT_NEAR(t_two_sided_p(0.0, 5.0), 1.0, 1e-12);
  // I_x(1, 1) = x; I_x(a, b) = 1 − I_{1−x}(b, a)
  EXPECT_NEAR(incomplete_beta_regularized(0.3, 1.0, 1.0), 0.3, 1e-12);
  EXPECT_NEAR(incomplete_beta_regularized(0.2, 2.5, 0.5) + incomplete_beta_regularized(0.8, 0.5, 2.5), 1.0,
              1e-12);
}

TEST(Stats, DegenerateGroupsGiveNaNNotACrash) {
  const std::vector<double> one{1.0}, same{2.0, 2.0, 2.0};
  EXPECT_TRUE(std::isnan(welch_t_test(one, kA).p));
  EXPECT_TRUE(std::isnan(welch_t_test(same, same).p));
}

}  // namespace
}  // namespace divcoll::analysis
