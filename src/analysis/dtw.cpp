#include "analysis/dtw.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/check.hpp"

namespace divcoll::analysis {

namespace {

double local_cost(const double* a, const double* b, int d, DtwCost cost) {
  double s = 0.0;
  for (int k = 0; k < d; ++k) {
    const double e = a[k] - b[k];
    s += e * e;
  }
  return cost == DtwCost::euclidean ? std::sqrt(s) : s;
}

}  // namespace

DtwResult dtw(const double* a, int n, const double* b, int m, int d, const DtwOptions& opt) {
  DIVCOLL_THROW_UNLESS(n >= 1 && m >= 1, "dtw: both series need at least one frame (got " << n << " and " << m
                                                                                          << ")");
  DIVCOLL_THROW_UNLESS(d >= 1, "dtw: at least one feature per frame is needed (got " << d << ")");
  for (long k = 0; k < static_cast<long>(n) * d; ++k)
    DIVCOLL_THROW_UNLESS(std::isfinite(a[k]), "dtw: entry " << k << " of the first series is not finite");
  for (long k = 0; k < static_cast<long>(m) * d; ++k)
    DIVCOLL_THROW_UNLESS(std::isfinite(b[k]), "dtw: entry " << k << " of the second series is not finite");

  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double slope = n > 1 ? static_cast<double>(m - 1) / (n - 1) : 0.0;
  const double r = opt.band;
  // columns j allowed in row i: floor(c − r) ≤ j ≤ ceil(c + r) with c = i·slope (all when no band); for
  // m > n the row is widened up to the column before the next row's first, so the band stays connected
  auto row_range = [&](int i, int& lo, int& hi) {
    if (opt.band < 0) {
      lo = 0;
      hi = m - 1;
      return;
    }
    const double c = i * slope;
    lo = std::max(0, static_cast<int>(std::floor(c - r + 1e-9)));
    hi = static_cast<int>(std::ceil(c + r - 1e-9));
    if (i + 1 < n) hi = std::max(hi, static_cast<int>(std::floor((i + 1) * slope - r + 1e-9)) - 1);
    hi = std::min(m - 1, hi);
  };

  std::vector<double> prev(m, kInf), cur(m, kInf);
  std::vector<int> kprev(m, 0), kcur(m, 0);
  const double diag_weight = opt.step == DtwStep::symmetric2 ? 2.0 : 1.0;
  for (int i = 0; i < n; ++i) {
    int lo, hi;
    row_range(i, lo, hi);
    std::fill(cur.begin(), cur.end(), kInf);
    for (int j = lo; j <= hi; ++j) {
      const double c = local_cost(a + static_cast<long>(i) * d, b + static_cast<long>(j) * d, d, opt.cost);
      if (i == 0 && j == 0) {
        cur[0] = c;
        kcur[0] = 1;
        continue;
      }
      // candidates in tie-break order: diagonal, vertical (i−1, j), horizontal (i, j−1)
      double best = kInf;
      int kbest = 0;
      if (i > 0 && j > 0 && prev[j - 1] < kInf) {
        best = prev[j - 1] + diag_weight * c;
        kbest = kprev[j - 1] + 1;
      }
      if (i > 0 && prev[j] < kInf && prev[j] + c < best) {
        best = prev[j] + c;
        kbest = kprev[j] + 1;
      }
      if (j > 0 && cur[j - 1] < kInf && cur[j - 1] + c < best) {
        best = cur[j - 1] + c;
        kbest = kcur[j - 1] + 1;
      }
      cur[j] = best;
      kcur[j] = kbest;
    }
    std::swap(prev, cur);
    std::swap(kprev, kcur);
  }
  const double dist = prev[m - 1];
  if (!(dist < kInf)) return {kInf, 0};
  return {opt.cost == DtwCost::squared_sqrt ? std::sqrt(dist) : dist, kprev[m - 1]};
}

}  // namespace divcoll::analysis
