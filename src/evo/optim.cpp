#include "evo/optim.hpp"

#include <cmath>

#include "common/dmath.hpp"

namespace divcoll::evo {

void Adam::step(std::vector<double>& p, std::vector<double> g, double lr, double clip_norm, int t) {
  if (m.size() != p.size()) m.assign(p.size(), 0.0), v.assign(p.size(), 0.0);
  double n2 = 0;
  for (double x : g) n2 += x * x;
  const double n = std::sqrt(n2);
  if (n > clip_norm)
    for (double& x : g) x *= clip_norm / n;
  const double b1 = 0.9, b2 = 0.999, eps = 1e-8;
  const double c1 = 1 - dmath::pow(b1, t), c2 = 1 - dmath::pow(b2, t);
  for (size_t q = 0; q < p.size(); ++q) {
    m[q] = b1 * m[q] + (1 - b1) * g[q];
    v[q] = b2 * v[q] + (1 - b2) * g[q] * g[q];
    p[q] -= lr * (m[q] / c1) / (std::sqrt(v[q] / c2) + eps);
  }
}

void normalized_step(std::vector<double>& p, const std::vector<double>& g, double lr) {
  double n2 = 0;
  for (double x : g) n2 += x * x;
  if (n2 <= 0) return;
  const double n = std::sqrt(n2);
  for (size_t q = 0; q < p.size(); ++q) p[q] -= lr * g[q] / n;
}

}  // namespace divcoll::evo
