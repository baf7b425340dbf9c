// DTW against the exact values of ANALYSIS.md §4.2 and its property tests
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/dtw.hpp"
#include "common/check.hpp"
#include "common/rng.hpp"

namespace divcoll::analysis {
namespace {

DtwResult dtw1(const std::vector<double>& a, const std::vector<double>& b, const DtwOptions& o = {}) {
  return dtw(a.data(), static_cast<int>(a.size()), b.data(), static_cast<int>(b.size()), 1, o);
}

TEST(Dtw, FastdtwDocExample) {
  const std::vector<double> x{1, 2, 3, 4, 5}, y{2, 3, 4};
  const DtwResult r = dtw1(x, y);
  EXPECT_DOUBLE_EQ(r.distance, 2.0);
  EXPECT_EQ(r.path_length, 5);
  DtwOptions sq;
  sq.cost = DtwCost::squared_sqrt;
  EXPECT_NEAR(dtw1(x, y, sq).distance, std::sqrt(2.0), 1e-12);
  DtwOptions s2;
  s2.step = DtwStep::symmetric2;
  const DtwResult r2 = dtw1(x, y, s2);
  EXPECT_DOUBLE_EQ(r2.distance, 2.0);
  EXPECT_DOUBLE_EQ(r2.distance / (5 + 3), 0.25);
}

TEST(Dtw, ShiftedSeriesWarpToZeroButNotInsideAZeroBand) {
  const std::vector<double> a{0, 0, 1, 2, 1, 0, 0}, b{0, 1, 2, 1, 0, 0, 0};
  const DtwResult r = dtw1(a, b);
  EXPECT_DOUBLE_EQ(r.distance, 0.0);
  EXPECT_EQ(r.path_length, 8);
  DtwOptions band0;
  band0.band = 0;
  EXPECT_DOUBLE_EQ(dtw1(a, b, band0).distance, 4.0);  // lock-step L1
  EXPECT_EQ(dtw1(a, b, band0).path_length, 7);
  DtwOptions band1;
  band1.band = 1;
  EXPECT_DOUBLE_EQ(dtw1(a, b, band1).distance, 0.0);
}

TEST(Dtw, MultivariateEuclideanCost) {
  const std::vector<double> A{0, 0, 1, 0, 2, 0, 3, 0}, B{0, 0, 0, 0, 1, 0, 2, 1, 3, 0};
  const DtwResult r = dtw(A.data(), 4, B.data(), 5, 2);
  EXPECT_DOUBLE_EQ(r.distance, 1.0);
  EXPECT_EQ(r.path_length, 5);
  EXPECT_DOUBLE_EQ(r.distance / r.path_length, 0.2);
}

std::vector<double> random_series(Rng& rng, int n, int d) {
  std::vector<double> v(static_cast<size_t>(n) * d);
  for (auto& x : v) x = normal(rng);
  return v;
}

TEST(Dtw, PropertiesOnRandomSeries) {
  Rng rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const int d = 1 + trial % 4, n = 5 + trial, m = trial % 2 ? n : 3 + 2 * trial;
    const auto x = random_series(rng, n, d), y = random_series(rng, m, d);
    const DtwResult xx = dtw(x.data(), n, x.data(), n, d);
    EXPECT_EQ(xx.distance, 0.0);
    EXPECT_EQ(xx.path_length, n);
    const DtwResult xy = dtw(x.data(), n, y.data(), m, d), yx = dtw(y.data(), m, x.data(), n, d);
    EXPECT_NEAR(xy.distance, yx.distance, 1e-12);
    EXPECT_GE(xy.path_length, std::max(n, m));
    EXPECT_LE(xy.path_length, n + m - 1);
    if (n == m) {
      double lockstep = 0.0;
      for (int i = 0; i < n; ++i) {
        double s = 0.0;
        for (int k = 0; k < d; ++k) s += (x[i * d + k] - y[i * d + k]) * (x[i * d + k] - y[i * d + k]);
        lockstep += std::sqrt(s);
      }
      EXPECT_LE(xy.distance, lockstep + 1e-12);
      DtwOptions b0;
      b0.band = 0;
      EXPECT_NEAR(dtw(x.data(), n, y.data(), m, d, b0).distance, lockstep, 1e-9);
    }
    double last = INFINITY;
    for (int r = 0; r <= std::max(n, m); ++r) {
      DtwOptions o;
      o.band = r;
      const double v = dtw(x.data(), n, y.data(), m, d, o).distance;
      EXPECT_LE(v, last + 1e-12) << "band " << r;
      last = v;
    }
    EXPECT_NEAR(last, xy.distance, 1e-12);  // a full band is no band
  }
}

TEST(Dtw, SlantedBandReachesTheEndForUnequalLengths) {
  Rng rng(3);
  const auto x = random_series(rng, 40, 2), y = random_series(rng, 10, 2);
  DtwOptions o;
  o.band = 0;
  const DtwResult r = dtw(x.data(), 40, y.data(), 10, 2, o);
  EXPECT_TRUE(std::isfinite(r.distance));
  EXPECT_GE(r.path_length, 40);
  EXPECT_LE(r.path_length, 49);
  const DtwResult t = dtw(y.data(), 10, x.data(), 40, 2, o);  // m > n: rows must be widened to connect
  EXPECT_TRUE(std::isfinite(t.distance));
  DtwOptions none;
  EXPECT_LE(dtw(x.data(), 40, y.data(), 10, 2, none).distance, r.distance + 1e-12);
  EXPECT_LE(dtw(y.data(), 10, x.data(), 40, 2, none).distance, t.distance + 1e-12);
}

TEST(Dtw, RefusesEmptyAndNonFiniteInput) {
  const std::vector<double> a{1, 2}, bad{1, NAN};
  EXPECT_THROW(dtw(a.data(), 0, a.data(), 2, 1), InputError);
  EXPECT_THROW(dtw(a.data(), 2, a.data(), 2, 0), InputError);
  EXPECT_THROW(dtw(a.data(), 2, bad.data(), 2, 1), InputError);
}

}  // namespace
}  // namespace divcoll::analysis
