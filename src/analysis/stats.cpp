#include "analysis/stats.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/check.hpp"
#include "common/dmath.hpp"
#include "common/rng.hpp"

namespace divcoll::analysis {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double sample_var(std::span<const double> x) {
  const double m = mean(x);
  double s = 0.0;
  for (double v : x) s += (v - m) * (v - m);
  return s / static_cast<double>(x.size() - 1);
}

// continued fraction of the incomplete beta function (modified Lentz)
double beta_cf(double x, double a, double b) {
  constexpr int kMaxIter = 1000;
  constexpr double kEps = 1e-15, kTiny = 1e-300;
  const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
  double c = 1.0, d = 1.0 - qab * x / qap;
  if (std::fabs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= kMaxIter; ++m) {
    const int m2 = 2 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) < kEps) break;
  }
  return h;
}

double normal_sf(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }
}  // namespace

double mean(std::span<const double> x) {
  if (x.empty()) return kNaN;
  double s = 0.0;
  for (double v : x) s += v;
  return s / static_cast<double>(x.size());
}

double sample_sd(std::span<const double> x) { return x.size() < 2 ? kNaN : std::sqrt(sample_var(x)); }

double sem(std::span<const double> x) {
  return x.size() < 2 ? kNaN : sample_sd(x) / std::sqrt(static_cast<double>(x.size()));
}

double quantile_linear(std::span<const double> sorted, double q) {
  if (sorted.empty()) return kNaN;
  DIVCOLL_THROW_UNLESS(q >= 0.0 && q <= 1.0, "quantile_linear: q must be in [0, 1], got " << q);
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  return sorted[lo] + frac * (sorted[hi] - sorted[lo]);
}

Interval bootstrap_ci(std::span<const double> x, uint64_t seed, int resamples, double level) {
  DIVCOLL_THROW_UNLESS(resamples >= 1, "bootstrap_ci: resamples must be >= 1, got " << resamples);
  DIVCOLL_THROW_UNLESS(level > 0.0 && level < 1.0, "bootstrap_ci: level must be in (0, 1), got " << level);
  if (x.empty()) return {kNaN, kNaN};
  if (x.size() == 1) return {x[0], x[0]};
  Rng rng(seed);
  std::vector<double> means(static_cast<size_t>(resamples));
  const size_t n = x.size();
  for (auto& mu : means) {
    double s = 0.0;
    for (size_t k = 0; k < n; ++k) s += x[uniform_int(rng, n)];
    mu = s / static_cast<double>(n);
  }
  std::sort(means.begin(), means.end());
  return {quantile_linear(means, (1.0 - level) / 2.0), quantile_linear(means, (1.0 + level) / 2.0)};
}

double incomplete_beta_regularized(double x, double a, double b) {
  DIVCOLL_THROW_UNLESS(a > 0.0 && b > 0.0, "incomplete_beta_regularized: a and b must be > 0");
  if (std::isnan(x)) return kNaN;
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double lbt = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * dmath::log(x) + b * std::log1p(-x);
  const double bt = dmath::exp(lbt);
  // the continued fraction converges fast for x < (a+1)/(a+b+2); use the symmetry otherwise
  if (x < (a + 1.0) / (a + b + 2.0)) return bt * beta_cf(x, a, b) / a;
  return 1.0 - bt * beta_cf(1.0 - x, b, a) / b;
}

double t_two_sided_p(double t, double df) {
  if (std::isnan(t) || !(df > 0.0)) return kNaN;
  if (std::isinf(t)) return 0.0;
  return incomplete_beta_regularized(df / (df + t * t), df / 2.0, 0.5);
}

TestResult welch_t_test(std::span<const double> a, std::span<const double> b) {
  if (a.size() < 2 || b.size() < 2) return {kNaN, kNaN, kNaN};
  const double n1 = static_cast<double>(a.size()), n2 = static_cast<double>(b.size());
  const double v1 = sample_var(a) / n1, v2 = sample_var(b) / n2;
  if (v1 + v2 == 0.0) return {kNaN, kNaN, kNaN};
  const double t = (mean(a) - mean(b)) / std::sqrt(v1 + v2);
  const double df = (v1 + v2) * (v1 + v2) / (v1 * v1 / (n1 - 1.0) + v2 * v2 / (n2 - 1.0));
  return {t, df, t_two_sided_p(t, df)};
}

TestResult student_t_test(std::span<const double> a, std::span<const double> b) {
  if (a.size() < 2 || b.size() < 2) return {kNaN, kNaN, kNaN};
  const double n1 = static_cast<double>(a.size()), n2 = static_cast<double>(b.size());
  const double df = n1 + n2 - 2.0;
  const double pooled = ((n1 - 1.0) * sample_var(a) + (n2 - 1.0) * sample_var(b)) / df;
  if (pooled == 0.0) return {kNaN, kNaN, kNaN};
  const double t = (mean(a) - mean(b)) / std::sqrt(pooled * (1.0 / n1 + 1.0 / n2));
  return {t, df, t_two_sided_p(t, df)};
}

TestResult mann_whitney_u(std::span<const double> a, std::span<const double> b) {
  const size_t n1 = a.size(), n2 = b.size();
  if (n1 == 0 || n2 == 0) return {kNaN, kNaN, kNaN};
  // ranks of the pooled sample, ties sharing their mean rank
  std::vector<std::pair<double, int>> all;
  all.reserve(n1 + n2);
  for (double v : a) all.emplace_back(v, 0);
  for (double v : b) all.emplace_back(v, 1);
  std::sort(all.begin(), all.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
  double rank_sum_a = 0.0, tie_term = 0.0;
  bool ties = false;
  for (size_t i = 0; i < all.size();) {
    size_t j = i;
    while (j + 1 < all.size() && all[j + 1].first == all[i].first) ++j;
    const double r = 0.5 * static_cast<double>(i + j) + 1.0;
    const double t = static_cast<double>(j - i + 1);
    if (t > 1) ties = true;
    tie_term += t * t * t - t;
    for (size_t k = i; k <= j; ++k)
      if (all[k].second == 0) rank_sum_a += r;
    i = j + 1;
  }
  const double N1 = static_cast<double>(n1), N2 = static_cast<double>(n2);
  const double u = rank_sum_a - N1 * (N1 + 1.0) / 2.0;
  const double u_small = std::min(u, N1 * N2 - u);
  if (!ties && n1 <= 50 && n2 <= 50) {
    // f[i][j][k]: arrangements of i a's and j b's with U = k; p = 2·P(U ≤ u_small), capped at 1
    const int U = static_cast<int>(std::lround(u_small));
    const int umax = static_cast<int>(n1 * n2);
    std::vector<std::vector<std::vector<double>>> f(
        n1 + 1, std::vector<std::vector<double>>(n2 + 1, std::vector<double>(umax + 1, 0.0)));
    for (size_t i = 0; i <= n1; ++i)
      for (size_t j = 0; j <= n2; ++j) {
        if (i == 0 || j == 0) {
          f[i][j][0] = 1.0;
          continue;
        }
        for (int k = 0; k <= static_cast<int>(i * j); ++k) {
          // the largest value is an a (it beats all j b's) or a b
          const double from_a = k >= static_cast<int>(j) ? f[i - 1][j][k - j] : 0.0;
          f[i][j][k] = from_a + f[i][j - 1][k];
        }
      }
    double total = 0.0, below = 0.0;
    for (int k = 0; k <= umax; ++k) {
      total += f[n1][n2][k];
      if (k <= U) below += f[n1][n2][k];
    }
    return {u, kNaN, std::min(1.0, 2.0 * below / total)};
  }
  const double mu = N1 * N2 / 2.0;
  const double n = N1 + N2;
  const double sigma = std::sqrt(N1 * N2 / 12.0 * ((n + 1.0) - tie_term / (n * (n - 1.0))));
  if (sigma == 0.0) return {u, kNaN, kNaN};
  const double z = (std::fabs(u - mu) - 0.5) / sigma;
  return {u, kNaN, std::min(1.0, 2.0 * normal_sf(std::max(z, 0.0)))};
}

}  // namespace divcoll::analysis
