// behaviour descriptor and uniqueness (SPEC §4.2, §4.4): see descriptor.hpp
#include "morph/descriptor.hpp"

#include <algorithm>
#include <cmath>

#include "common/check.hpp"
#include "common/dmath.hpp"

namespace divcoll::morph {
namespace {

constexpr double kTinyExtent = 1e-12;  // u, floor of every extent we divide by

// fraction of the n points whose mirror image (through `mirror`) is within tolerance of some point
template <class Mirror>
double mirror_fraction(const std::vector<double>& pos, int n, Mirror mirror) {
  int matched = 0;
  for (int i = 0; i < n; ++i) {
    const auto [mx, my] = mirror(pos[2 * i], pos[2 * i + 1]);
    for (int j = 0; j < n; ++j)
      if (dmath::hypot(pos[2 * j] - mx, pos[2 * j + 1] - my) <= kMirrorTolerance) {
        ++matched;
        break;
      }
  }
  return n > 0 ? static_cast<double>(matched) / n : 0.0;
}

}  // namespace

Descriptor descriptor(const Agent& g) {
  const int n = static_cast<int>(g.rest_pos.size() / 2);
  DIVCOLL_DEMAND(n > 0);
  const auto& p = g.rest_pos;

  // bounding box and centroid
  double min_x = p[0], max_x = p[0], min_y = p[1], max_y = p[1], sum_x = 0, sum_y = 0;
  for (int i = 0; i < n; ++i) {
    min_x = std::min(min_x, p[2 * i]);
    max_x = std::max(max_x, p[2 * i]);
    min_y = std::min(min_y, p[2 * i + 1]);
    max_y = std::max(max_y, p[2 * i + 1]);
    sum_x += p[2 * i];
    sum_y += p[2 * i + 1];
  }
  const double w = std::max(max_x - min_x, kTinyExtent), h = std::max(max_y - min_y, kTinyExtent);
  const double mean_x = sum_x / n, mean_y = sum_y / n;

  // spread of the heights
  double var_y = 0;
  for (int i = 0; i < n; ++i) var_y += (p[2 * i + 1] - mean_y) * (p[2 * i + 1] - mean_y);
  var_y /= n;

  // mirror lines through the box centre
  const double cx = 0.5 * (min_x + max_x), cy = 0.5 * (min_y + max_y);
  const double sym_v = mirror_fraction(p, n, [cx](double x, double y) { return std::array{2 * cx - x, y}; });
  const double sym_h = mirror_fraction(p, n, [cy](double x, double y) { return std::array{x, 2 * cy - y}; });

  Descriptor d;
  d[0] = h / kLatticeHeight;
  d[1] = w / kLatticeWidth;
  d[2] = w / h;
  d[3] = g.n_active() / (w * h);
  d[4] = (mean_x - min_x) / w;
  d[5] = (mean_y - min_y) / h;
  d[6] = std::sqrt(var_y);
  d[7] = sym_v;
  d[8] = sym_h;
  return d;
}

std::vector<double> uniqueness(const std::vector<Descriptor>& pool, int k) {
  DIVCOLL_THROW_UNLESS(k >= 1, "uniqueness: k must be at least 1, got " << k);
  const int n = static_cast<int>(pool.size());
  std::vector<double> u(n, 0.0);
  if (n <= 1) return u;

  // z-score every dimension over the pool; a constant dimension becomes all zeros
  std::vector<Descriptor> z(pool);
  for (int d = 0; d < kDescriptorSize; ++d) {
    double mean = 0, var = 0;
    for (const auto& x : pool) mean += x[d];
    mean /= n;
    for (const auto& x : pool) var += (x[d] - mean) * (x[d] - mean);
    const double sd = std::sqrt(var / n);
    const bool flat = sd <= 1e-12 * std::max(1.0, std::abs(mean));
    for (int i = 0; i < n; ++i) z[i][d] = flat ? 0.0 : (pool[i][d] - mean) / sd;
  }

  // mean distance to the k nearest others
  const int kk = std::min(k, n - 1);
  std::vector<double> dist(n - 1);
  for (int i = 0; i < n; ++i) {
    int m = 0;
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      double s = 0;
      for (int d = 0; d < kDescriptorSize; ++d) s += (z[i][d] - z[j][d]) * (z[i][d] - z[j][d]);
      dist[m++] = std::sqrt(s);
    }
    std::partial_sort(dist.begin(), dist.begin() + kk, dist.end());
    double sum = 0;
    for (int q = 0; q < kk; ++q) sum += dist[q];
    u[i] = sum / kk;
  }
  return u;
}

}  // namespace divcoll::morph
