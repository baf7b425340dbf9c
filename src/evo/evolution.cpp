#include "evo/evolution.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/dmath.hpp"
#include "morph/body.hpp"

namespace divcoll::evo {

morph::Descriptor agent_descriptor(const morph::Agent& a) { return morph::descriptor(a); }

morph::Descriptor spring_layout_descriptor(const morph::Agent& a) {
  morph::Descriptor d = agent_descriptor(a);
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (size_t m = 0; m < a.rest_pos.size() / 2; ++m) {
    x0 = std::min(x0, a.rest_pos[2 * m]), x1 = std::max(x1, a.rest_pos[2 * m]);
    y0 = std::min(y0, a.rest_pos[2 * m + 1]), y1 = std::max(y1, a.rest_pos[2 * m + 1]);
  }
  const double tol = morph::kMirrorTolerance;
  auto near = [&](double ax, double ay, double bx, double by) { return dmath::hypot(ax - bx, ay - by) <= tol; };
  for (int axis = 0; axis < 2; ++axis) {
    int active = 0, matched = 0;
    for (size_t r = 0; r < a.spring_i.size(); ++r) {
      if (a.amplitude[r] == 0) continue;
      ++active;
      auto mirror = [&](int m, double& x, double& y) {
        x = a.rest_pos[2 * m], y = a.rest_pos[2 * m + 1];
        if (axis == 0) x = x0 + x1 - x;
        else y = y0 + y1 - y;
      };
      double px, py, qx, qy;
      mirror(a.spring_i[r], px, py);
      mirror(a.spring_j[r], qx, qy);
      for (size_t t = 0; t < a.spring_i.size(); ++t) {
        if (a.amplitude[t] == 0) continue;
        const double ix = a.rest_pos[2 * a.spring_i[t]], iy = a.rest_pos[2 * a.spring_i[t] + 1];
        const double jx = a.rest_pos[2 * a.spring_j[t]], jy = a.rest_pos[2 * a.spring_j[t] + 1];
        if ((near(px, py, ix, iy) && near(qx, qy, jx, jy)) || (near(px, py, jx, jy) && near(qx, qy, ix, iy))) {
          ++matched;
          break;
        }
      }
    }
    d[7 + axis] = active ? static_cast<double>(matched) / active : 0.0;
  }
  return d;
}

morph::Agent make_offspring(const morph::Agent& parent, Rng& rng, const MutationOptions& opt, const GdOptions& gd) {
  morph::Agent child = parent;
  // genotype: body bits (repaired to a valid body), then spring bits
  if (!opt.body_fixed) child.cells = morph::mutate_body(parent.cells, rng, opt.body_flip_p);
  if (!opt.springs_fixed) child.springs = morph::mutate_springs(parent.springs, rng, opt.spring_flip_p);
  const morph::Agent g = morph::agent_geometry(child.cells, child.springs);
  child.spring_i = g.spring_i;
  child.spring_j = g.spring_j;
  child.amplitude = g.amplitude;
  if (child.cells != parent.cells) {
    child.rest_pos = g.rest_pos;  // a new body starts from its lattice points
  }
  morph::update_rest_lengths(child);
  // rest positions: N(0, sd²) per coordinate, kept only if every rest length stays within its bounds
  if (opt.rest_moves && opt.rest_jitter_sd > 0) {
    std::vector<double> delta(child.rest_pos.size());
    for (double& d : delta) d = normal(rng, 0.0, opt.rest_jitter_sd);
    move_rest_positions(child, delta, gd);
  }
  return child;
}

namespace {
// rank of each value among `v` (0 = lowest); tied values share their mean rank
std::vector<double> ranks(const std::vector<double>& v) {
  std::vector<int> order(v.size());
  for (size_t i = 0; i < v.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return v[a] < v[b]; });
  std::vector<double> r(v.size());
  for (size_t q = 0; q < order.size();) {
    size_t end = q + 1;
    while (end < order.size() && v[order[end]] == v[order[q]]) ++end;
    const double mean = 0.5 * static_cast<double>(q + end - 1);
    for (size_t k = q; k < end; ++k) r[order[k]] = mean;
    q = end;
  }
  return r;
}
}  // namespace

std::vector<int> select_survivors(const std::vector<Individual>& pool, int keep, int k,
                                  std::vector<double>* uniqueness_out, bool rank) {
  const int n = static_cast<int>(pool.size());
  std::vector<int> alive(n);
  for (int i = 0; i < n; ++i) alive[i] = i;
  auto uniq_of = [&](const std::vector<int>& members) {
    std::vector<morph::Descriptor> d;
    for (int i : members) d.push_back(pool[i].descriptor);
    return morph::uniqueness(d, k);
  };
  if (uniqueness_out) *uniqueness_out = uniq_of(alive);
  auto failed = [&](int i) {
    return pool[i].train.status != sim::Status::ok || !std::isfinite(pool[i].train.fitness_bl);
  };
  while (static_cast<int>(alive.size()) > keep) {
    // failed members go first, the lowest index first
    int victim = -1;
    for (int q = 0; q < static_cast<int>(alive.size()) && victim < 0; ++q)
      if (failed(alive[q])) victim = q;
    if (victim < 0) {
      const std::vector<double> u = uniq_of(alive);
      std::vector<double> f;
      for (int i : alive) f.push_back(pool[i].train.fitness_bl);
      const double fmin = *std::min_element(f.begin(), f.end());
      const std::vector<double> fr = rank ? ranks(f) : std::vector<double>{}, ur = rank ? ranks(u) : std::vector<double>{};
      double worst = std::numeric_limits<double>::infinity();
      for (int q = 0; q < static_cast<int>(alive.size()); ++q) {
        const double score = rank ? (fr[q] + 1) * (ur[q] + 1) : (f[q] - fmin + 1e-6) * u[q];
        if (score < worst) worst = score, victim = q;  // ties: the lowest index
      }
    }
    alive.erase(alive.begin() + victim);
  }
  return alive;
}

}  // namespace divcoll::evo
