// PaCMAP (ANALYSIS.md §1) against the recipes of ANALYSIS.md §4.1: two separated blobs, intrinsic 2-D
// data, the pieces (coefficients vs finite differences, find_weight, the first Adam step, pair
// invariants, the σ floor), integer-cell occupancy, determinism, bad input, and a printed n = 3000 time
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "analysis/pacmap.hpp"
#include "common/check.hpp"
#include "common/rng.hpp"

namespace {

using divcoll::InputError;
using divcoll::Rng;
namespace an = divcoll::analysis;

constexpr int kD = 32;

struct Data {
  std::vector<double> X;  // n × D row-major
  std::vector<uint8_t> label;
  int n = 0, D = 0;
};

// two N(0, I_D) blobs of `per` points each, the second shifted by 10/√D per coordinate (means 10 apart)
Data two_blobs(int per, uint64_t seed) {
  Data d;
  d.n = 2 * per;
  d.D = kD;
  Rng rng = divcoll::make_rng(seed, 100, 0);
  const double shift = 10.0 / std::sqrt(static_cast<double>(kD));
  for (int i = 0; i < d.n; ++i) {
    const uint8_t b = i < per ? 0 : 1;
    d.label.push_back(b);
    for (int k = 0; k < kD; ++k) d.X.push_back(divcoll::normal(rng) + (b ? shift : 0.0));
  }
  return d;
}

// n points uniform in [0,10]², mapped into R^32 by a random orthonormal 32×2 matrix, plus N(0, 0.01²) noise
Data intrinsic_2d(int n, uint64_t seed) {
  Data d;
  d.n = n;
  d.D = kD;
  Rng rng = divcoll::make_rng(seed, 101, 0);
  // Gram–Schmidt on two Gaussian vectors
  std::vector<double> q0(kD), q1(kD);
  for (int k = 0; k < kD; ++k) q0[k] = divcoll::normal(rng);
  for (int k = 0; k < kD; ++k) q1[k] = divcoll::normal(rng);
  double n0 = 0;
  for (double v : q0) n0 += v * v;
  for (double& v : q0) v /= std::sqrt(n0);
  double dot = 0;
  for (int k = 0; k < kD; ++k) dot += q0[k] * q1[k];
  for (int k = 0; k < kD; ++k) q1[k] -= dot * q0[k];
  double n1 = 0;
  for (double v : q1) n1 += v * v;
  for (double& v : q1) v /= std::sqrt(n1);
  for (int i = 0; i < n; ++i) {
    const double u = 10.0 * divcoll::uniform01(rng), w = 10.0 * divcoll::uniform01(rng);
    for (int k = 0; k < kD; ++k) d.X.push_back(u * q0[k] + w * q1[k] + divcoll::normal(rng, 0.0, 0.01));
    d.label.push_back(0);
  }
  return d;
}

// the k nearest other points of each row (brute force, by index exclusion), n × k
std::vector<int> knn(const std::vector<double>& P, int n, int dim, int k) {
  std::vector<int> out(static_cast<size_t>(n) * k);
  std::vector<std::pair<double, int>> row;
  for (int i = 0; i < n; ++i) {
    row.clear();
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      double s = 0;
      for (int a = 0; a < dim; ++a) {
        const double diff = P[static_cast<size_t>(i) * dim + a] - P[static_cast<size_t>(j) * dim + a];
        s += diff * diff;
      }
      row.emplace_back(s, j);
    }
    std::partial_sort(row.begin(), row.begin() + k, row.end());
    for (int c = 0; c < k; ++c) out[static_cast<size_t>(i) * k + c] = row[c].second;
  }
  return out;
}

// mean over points of |10-NN in X ∩ 10-NN in Y| / 10
double nn_preservation(const Data& d, const std::vector<double>& Y) {
  const int k = 10;
  const auto hi = knn(d.X, d.n, d.D, k), lo = knn(Y, d.n, 2, k);
  double sum = 0;
  for (int i = 0; i < d.n; ++i) {
    const std::set<int> a(hi.begin() + i * k, hi.begin() + (i + 1) * k);
    int common = 0;
    for (int c = 0; c < k; ++c) common += a.count(lo[static_cast<size_t>(i) * k + c]) ? 1 : 0;
    sum += static_cast<double>(common) / k;
  }
  return sum / d.n;
}

// mean over points of the fraction of its 10 nearest 2-D neighbours with its own label
double label_purity(const Data& d, const std::vector<double>& Y) {
  const int k = 10;
  const auto lo = knn(Y, d.n, 2, k);
  double sum = 0;
  for (int i = 0; i < d.n; ++i) {
    int same = 0;
    for (int c = 0; c < k; ++c) same += d.label[lo[static_cast<size_t>(i) * k + c]] == d.label[i] ? 1 : 0;
    sum += static_cast<double>(same) / k;
  }
  return sum / d.n;
}

bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// the pair-set invariants of §4.1 item 3 for per-point counts (nn, mn, fp)
void expect_pair_invariants(const an::PacmapPairs& p, int n, int nn, int mn, int fp) {
  ASSERT_EQ(p.nn.size(), static_cast<size_t>(n) * nn);
  ASSERT_EQ(p.mn.size(), static_cast<size_t>(n) * mn);
  ASSERT_EQ(p.fp.size(), static_cast<size_t>(n) * fp);
  for (int i = 0; i < n; ++i) {
    std::set<int> nnset, mnset, fpset;
    for (int c = 0; c < nn; ++c) {
      const auto [a, j] = p.nn[static_cast<size_t>(i) * nn + c];
      EXPECT_EQ(a, i) << "NN pairs are row-major by i";
      EXPECT_NE(j, i) << "self NN pair at " << i;
      EXPECT_TRUE(j >= 0 && j < n);
      EXPECT_TRUE(nnset.insert(j).second) << "duplicate NN partner " << j << " of " << i;
    }
    for (int c = 0; c < mn; ++c) {
      const auto [a, j] = p.mn[static_cast<size_t>(i) * mn + c];
      EXPECT_EQ(a, i) << "MN pairs are row-major by i";
      EXPECT_NE(j, i) << "self MN pair at " << i;
      EXPECT_TRUE(j >= 0 && j < n);
      EXPECT_TRUE(mnset.insert(j).second) << "duplicate MN partner " << j << " of " << i;
    }
    for (int c = 0; c < fp; ++c) {
      const auto [a, j] = p.fp[static_cast<size_t>(i) * fp + c];
      EXPECT_EQ(a, i) << "FP pairs are row-major by i";
      EXPECT_NE(j, i) << "self FP pair at " << i;
      EXPECT_TRUE(j >= 0 && j < n);
      EXPECT_TRUE(fpset.insert(j).second) << "duplicate FP partner " << j << " of " << i;
      EXPECT_EQ(nnset.count(j), 0u) << "FP partner " << j << " of " << i << " is one of its NN partners";
    }
  }
}

// ---- §4.1 item 1: two separated blobs -------------------------------------------------------------

TEST(Pacmap, TwoSeparatedBlobsStayApartAndPure) {
  for (uint64_t seed : {1u, 2u}) {
    const Data d = two_blobs(300, seed);
    an::PacmapOptions o;
    o.seed = seed;
    const std::vector<double> Y = an::pacmap_fit(d.X.data(), d.n, d.D, o);
    ASSERT_TRUE(all_finite(Y));
    double c[2][2] = {{0, 0}, {0, 0}};
    int cnt[2] = {0, 0};
    for (int i = 0; i < d.n; ++i) {
      c[d.label[i]][0] += Y[2 * i];
      c[d.label[i]][1] += Y[2 * i + 1];
      ++cnt[d.label[i]];
    }
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a) c[b][a] /= cnt[b];
    double rmax[2] = {0, 0}, rmean[2] = {0, 0};
    for (int i = 0; i < d.n; ++i) {
      const int b = d.label[i];
      const double r = std::hypot(Y[2 * i] - c[b][0], Y[2 * i + 1] - c[b][1]);
      rmax[b] = std::max(rmax[b], r);
      rmean[b] += r / cnt[b];
    }
    const double cdist = std::hypot(c[0][0] - c[1][0], c[0][1] - c[1][1]);
    const double purity = label_purity(d, Y);
    const double pres = nn_preservation(d, Y);
    std::printf("[pacmap] blobs seed %llu: purity %.4f, centroid distance %.2f, mean radius %.2f/%.2f, "
                "max radius %.2f/%.2f, 10-NN preservation %.3f\n",
                static_cast<unsigned long long>(seed), purity, cdist, rmean[0], rmean[1], rmax[0], rmax[1], pres);
    EXPECT_GE(purity, 0.98);
    EXPECT_GT(cdist, 2.0 * (rmax[0] + rmax[1]));
    EXPECT_GT(pres, 0.05) << "random baseline is 10/599 = 0.017";
  }
}

// ---- §4.1 item 2: intrinsic 2-D data ---------------------------------------------------------------

TEST(Pacmap, IntrinsicTwoDimensionalDataKeepsNeighbours) {
  for (uint64_t seed : {1u, 2u}) {
    const Data d = intrinsic_2d(600, seed);
    an::PacmapOptions o;
    o.seed = seed;
    const std::vector<double> Y = an::pacmap_fit(d.X.data(), d.n, d.D, o);
    ASSERT_TRUE(all_finite(Y));
    const double pres = nn_preservation(d, Y);
    std::printf("[pacmap] intrinsic 2-D seed %llu: 10-NN preservation %.3f\n", static_cast<unsigned long long>(seed),
                pres);
    EXPECT_GE(pres, 0.6);
  }
}

// ---- §4.1 item 3: the pieces -------------------------------------------------------------------------

// the three pair losses of §1.7 as functions of (y_i, y_j)
double pair_loss(char type, const double* yi, const double* yj, double w) {
  const double dx = yi[0] - yj[0], dy = yi[1] - yj[1];
  const double dt = 1.0 + dx * dx + dy * dy;
  if (type == 'n') return w * dt / (10.0 + dt);
  if (type == 'm') return w * dt / (10000.0 + dt);
  return w / (1.0 + dt);
}

TEST(Pacmap, CoefficientsMatchCentralDifferencesOfTheLosses) {
  EXPECT_NEAR(an::pacmap_coefficient('n', 4.0, 1.0), 20.0 / 196.0, 1e-15);
  EXPECT_NEAR(an::pacmap_coefficient('n', 4.0, 1.0), 0.10204, 1e-5);
  EXPECT_NEAR(an::pacmap_coefficient('m', 4.0, 1.0), 20000.0 / (10004.0 * 10004.0), 1e-15);
  EXPECT_NEAR(an::pacmap_coefficient('f', 4.0, 1.0), -2.0 / 25.0, 1e-15);
  EXPECT_LT(an::pacmap_coefficient('f', 4.0, 1.0), 0.0) << "FP is repulsive";
  EXPECT_THROW(an::pacmap_coefficient('x', 4.0, 1.0), InputError);

  Rng rng = divcoll::make_rng(7, 102, 0);
  const double h = 1e-6;
  for (char type : {'n', 'm', 'f'}) {
    for (int trial = 0; trial < 20; ++trial) {
      // separations from 0 to ~30 cover all regimes, including MN's near-linear one
      const double scale = trial < 10 ? 2.0 : 15.0;
      double yi[2] = {scale * divcoll::normal(rng), scale * divcoll::normal(rng)};
      double yj[2] = {scale * divcoll::normal(rng), scale * divcoll::normal(rng)};
      const double w = 0.5 + 3.0 * divcoll::uniform01(rng);
      const double dx = yi[0] - yj[0], dy = yi[1] - yj[1];
      const double c = an::pacmap_coefficient(type, 1.0 + dx * dx + dy * dy, w);
      const double analytic_i[2] = {c * dx, c * dy};
      for (int a = 0; a < 2; ++a) {
        // ∂L/∂y_i
        double p[2] = {yi[0], yi[1]}, m[2] = {yi[0], yi[1]};
        p[a] += h;
        m[a] -= h;
        const double fd_i = (pair_loss(type, p, yj, w) - pair_loss(type, m, yj, w)) / (2 * h);
        EXPECT_NEAR(fd_i, analytic_i[a], 1e-7 + 1e-6 * std::abs(analytic_i[a])) << type << " trial " << trial;
        // ∂L/∂y_j = −c·y_ij
        double pj[2] = {yj[0], yj[1]}, mj[2] = {yj[0], yj[1]};
        pj[a] += h;
        mj[a] -= h;
        const double fd_j = (pair_loss(type, yi, pj, w) - pair_loss(type, yi, mj, w)) / (2 * h);
        EXPECT_NEAR(fd_j, -analytic_i[a], 1e-7 + 1e-6 * std::abs(analytic_i[a])) << type << " trial " << trial;
      }
    }
  }
}

TEST(Pacmap, FindWeightFollowsTheThreePhases) {
  const auto w0 = an::pacmap_weights(0);
  EXPECT_DOUBLE_EQ(w0.w_mn, 1000.0);
  EXPECT_DOUBLE_EQ(w0.w_nn, 2.0);
  EXPECT_DOUBLE_EQ(w0.w_fp, 1.0);
  const auto w99 = an::pacmap_weights(99);
  EXPECT_NEAR(w99.w_mn, 12.97, 1e-12);
  EXPECT_DOUBLE_EQ(w99.w_nn, 2.0);
  EXPECT_DOUBLE_EQ(w99.w_fp, 1.0);
  const auto w100 = an::pacmap_weights(100);
  EXPECT_DOUBLE_EQ(w100.w_mn, 3.0);
  EXPECT_DOUBLE_EQ(w100.w_nn, 3.0);
  EXPECT_DOUBLE_EQ(w100.w_fp, 1.0);
  const auto w200 = an::pacmap_weights(200);
  EXPECT_DOUBLE_EQ(w200.w_mn, 0.0);
  EXPECT_DOUBLE_EQ(w200.w_nn, 1.0);
  EXPECT_DOUBLE_EQ(w200.w_fp, 1.0);
  EXPECT_DOUBLE_EQ(an::pacmap_weights(449).w_nn, 1.0);
  // the ramp divides by P1 itself
  an::PacmapOptions o;
  o.phase_iters[0] = 50;
  EXPECT_NEAR(an::pacmap_weights(25, o).w_mn, 501.5, 1e-12);
  EXPECT_DOUBLE_EQ(an::pacmap_weights(50, o).w_nn, 3.0);
  EXPECT_DOUBLE_EQ(an::pacmap_weights(150, o).w_nn, 1.0);
}

TEST(Pacmap, FirstAdamStepMovesEachCoordinateByLrTimesSign) {
  for (double lr : {1.0, 0.25}) {
    const std::vector<double> g = {0.3, -2.0, 150.0, -1e-2, 0.0, 7.5};
    std::vector<double> y = {1.0, 2.0, -3.0, 0.5, 4.0, 0.0};
    const std::vector<double> y0 = y;
    an::AdamState s;
    an::pacmap_adam_step(y, g, s, 0, lr);
    ASSERT_EQ(s.m.size(), g.size());
    for (size_t q = 0; q < g.size(); ++q) {
      EXPECT_NEAR(s.m[q], 0.1 * g[q], 1e-15 * std::abs(g[q]));
      EXPECT_NEAR(s.v[q], 0.001 * g[q] * g[q], 1e-15 * g[q] * g[q]);
      const double sign = g[q] > 0 ? 1.0 : (g[q] < 0 ? -1.0 : 0.0);
      // exact first step: lr·√0.001·g / (√0.001·|g| + 1e-7), i.e. lr·sign(g) up to the ε term
      const double exact = lr * std::sqrt(0.001) * g[q] / (std::sqrt(0.001) * std::abs(g[q]) + 1e-7);
      EXPECT_NEAR(y0[q] - y[q], exact, 1e-12) << q;
      // ... within the ε term's share, 1e-7 / (√0.001·|g|)
      EXPECT_NEAR(y0[q] - y[q], lr * sign, lr * 1e-7 / (std::sqrt(0.001) * std::abs(g[q]) + 1e-300) + 1e-15) << q;
      if (std::abs(g[q]) >= 1.0) {
        EXPECT_NEAR(y0[q] - y[q], lr * sign, 1e-5 * lr) << q;
      }
    }
  }
  // mismatched sizes are caller mistakes
  std::vector<double> y = {0.0, 0.0};
  an::AdamState s;
  EXPECT_THROW(an::pacmap_adam_step(y, {1.0}, s, 0, 1.0), InputError);
}

TEST(Pacmap, PairInvariantsAndExactNeighbours) {
  const Data d = two_blobs(300, 3);
  an::PacmapOptions o;
  o.seed = 3;
  const std::vector<double> Xp = an::pacmap_preprocess(d.X.data(), d.n, d.D);
  const an::PacmapPairs p = an::pacmap_pairs(Xp, d.n, d.D, o);
  expect_pair_invariants(p, d.n, 10, 5, 20);
  // every NN partner is among the 60 exact nearest candidates (§1.3: NN pairs come from those)
  const auto cand = knn(d.X, d.n, d.D, 60);
  for (int i = 0; i < d.n; ++i) {
    const std::set<int> c(cand.begin() + i * 60, cand.begin() + (i + 1) * 60);
    for (int t = 0; t < 10; ++t) EXPECT_EQ(c.count(p.nn[static_cast<size_t>(i) * 10 + t].second), 1u) << i;
  }
  // MN partners lie mostly beyond the nearest neighbours: 2nd-nearest of 6 random points
  int far = 0;
  const auto near10 = knn(d.X, d.n, d.D, 10);
  for (int i = 0; i < d.n; ++i) {
    const std::set<int> c(near10.begin() + i * 10, near10.begin() + (i + 1) * 10);
    for (int t = 0; t < 5; ++t) far += c.count(p.mn[static_cast<size_t>(i) * 5 + t].second) ? 0 : 1;
  }
  EXPECT_GT(far, d.n * 5 * 9 / 10);
}

// the guards of §1.1 for small n: counts shrink, invariants hold, samplers terminate, fits stay finite
TEST(Pacmap, SmallSampleGuards) {
  struct Case {
    int n, nn, mn, fp;
  };
  // n = 4..6: int(n/3.5) = 1 → (1, 0, 2); n = 7: (2, 1, 4); n = 20: (5, 2, 10); n = 35: (10, 5, 20);
  // n >= 36: the defaults
  for (const Case c : {Case{4, 1, 0, 2}, Case{5, 1, 0, 2}, Case{6, 1, 0, 2}, Case{7, 2, 1, 4}, Case{20, 5, 2, 10},
                       Case{35, 10, 5, 20}, Case{36, 10, 5, 20}, Case{61, 10, 5, 20}}) {
    Rng rng = divcoll::make_rng(9, 103, static_cast<uint64_t>(c.n));
    std::vector<double> X(static_cast<size_t>(c.n) * 3);
    for (double& x : X) x = divcoll::normal(rng);
    an::PacmapOptions o;
    const std::vector<double> Xp = an::pacmap_preprocess(X.data(), c.n, 3);
    const an::PacmapPairs p = an::pacmap_pairs(Xp, c.n, 3, o);
    SCOPED_TRACE("n = " + std::to_string(c.n));
    expect_pair_invariants(p, c.n, c.nn, c.mn, c.fp);
    EXPECT_TRUE(all_finite(an::pacmap_fit(X.data(), c.n, 3, o)));
  }
  // 5 MN rounds among 8 points (1 + 5 + 1 < 8, no rescaling): rounds 2–4 have only 5, 4, 3 eligible
  // points, fewer than the 6 draws (the library would loop forever there)
  {
    Rng rng = divcoll::make_rng(9, 104, 0);
    std::vector<double> X(8 * 3);
    for (double& x : X) x = divcoll::normal(rng);
    an::PacmapOptions o;
    o.n_neighbors = 1;
    o.mn_ratio = 5.0;
    o.fp_ratio = 1.0;
    const an::PacmapPairs p = an::pacmap_pairs(an::pacmap_preprocess(X.data(), 8, 3), 8, 3, o);
    expect_pair_invariants(p, 8, 1, 5, 1);
  }
}

TEST(Pacmap, SigmaFloorWithExactDuplicatesGivesFiniteOutput) {
  Data d = two_blobs(300, 4);
  // rows 1..9 are exact copies of row 0: 9 duplicates, so σ_0 = (r3 + r4 + r5)/3 = 0 → floor 1e-10
  for (int i = 1; i < 10; ++i) std::copy(d.X.begin(), d.X.begin() + kD, d.X.begin() + static_cast<ptrdiff_t>(i) * kD);
  // and rows 300..307 are 8 copies of one point of the other blob
  for (int i = 301; i < 308; ++i)
    std::copy(d.X.begin() + 300 * kD, d.X.begin() + 301 * kD, d.X.begin() + static_cast<ptrdiff_t>(i) * kD);
  an::PacmapOptions o;
  o.seed = 4;
  const std::vector<double> Xp = an::pacmap_preprocess(d.X.data(), d.n, d.D);
  const an::PacmapPairs p = an::pacmap_pairs(Xp, d.n, d.D, o);
  expect_pair_invariants(p, d.n, 10, 5, 20);
  // i is excluded by index, so its duplicates are its nearest neighbours (scaled distance 0)
  for (int t = 0; t < 9; ++t) {
    const int j = p.nn[t].second;
    EXPECT_TRUE(j >= 1 && j < 10) << "NN partner " << j << " of the duplicated point 0";
  }
  const std::vector<double> Y = an::pacmap_fit(d.X.data(), d.n, d.D, o);
  EXPECT_TRUE(all_finite(Y));
  // duplicates land close together
  for (int i = 1; i < 10; ++i) EXPECT_LT(std::hypot(Y[2 * i] - Y[0], Y[2 * i + 1] - Y[1]), 1.0);
}

// a cluster of 100 duplicates is more than the 60 kNN candidates: ties are broken by index (the exact
// path that recomputes every distance of such a row), and σ_i = 1e-10 makes every scaled distance 0
TEST(Pacmap, LargeDuplicateClusterBreaksTiesByIndex) {
  const int n = 200;
  Rng rng = divcoll::make_rng(13, 108, 0);
  std::vector<double> X(static_cast<size_t>(n) * kD);
  for (double& x : X) x = divcoll::normal(rng);
  for (int i = 1; i < 100; ++i) std::copy(X.begin(), X.begin() + kD, X.begin() + static_cast<ptrdiff_t>(i) * kD);
  an::PacmapOptions o;
  const an::PacmapPairs p = an::pacmap_pairs(an::pacmap_preprocess(X.data(), n, kD), n, kD, o);
  expect_pair_invariants(p, n, 10, 5, 20);
  for (int i : {0, 5, 50, 99}) {
    std::vector<int> want;
    for (int j = 0; static_cast<int>(want.size()) < 10; ++j)
      if (j != i) want.push_back(j);
    for (int t = 0; t < 10; ++t) EXPECT_EQ(p.nn[static_cast<size_t>(i) * 10 + t].second, want[t]) << "point " << i;
  }
  EXPECT_TRUE(all_finite(an::pacmap_fit(X.data(), n, kD, o)));
}

TEST(Pacmap, PreprocessShiftsScalesAndCentres) {
  // 4 × 2: global min −1; shifted [0 4; 2 1; 4 2; 1 3], max 4 → [0 1; .5 .25; 1 .5; .25 .75];
  // column means (0.4375, 0.625) subtracted
  const std::vector<double> X = {-1.0, 3.0, 1.0, 0.0, 3.0, 1.0, 0.0, 2.0};
  const std::vector<double> Xp = an::pacmap_preprocess(X.data(), 4, 2);
  const std::vector<double> want = {-0.4375, 0.375, 0.0625, -0.375, 0.5625, -0.125, -0.1875, 0.125};
  ASSERT_EQ(Xp.size(), want.size());
  for (size_t q = 0; q < want.size(); ++q) EXPECT_NEAR(Xp[q], want[q], 1e-15) << q;
  // a constant input (max 0 after the shift) is centred to zeros instead of dividing 0/0
  const std::vector<double> C(8, 2.5);
  for (double v : an::pacmap_preprocess(C.data(), 4, 2)) EXPECT_EQ(v, 0.0);
}

TEST(Pacmap, PcaInitFollowsTheTopPrincipalAxes) {
  // x_i = 3 + a_i·u + b_i·w with u = (1, 2, 0, 2)/3, w = (0, 0, 1, 0), a linear and centred, and b the
  // pattern (+1, −1, −1, +1) repeated: Σa = Σb = Σab = 0 exactly, so the covariance is var(a)·uuᵀ +
  // var(b)·wwᵀ and the principal axes are exactly u, then w
  const int n = 400, D = 4;
  const double u[4] = {1.0 / 3, 2.0 / 3, 0.0, 2.0 / 3};
  std::vector<double> Xp(static_cast<size_t>(n) * D), a(n), b(n);
  for (int i = 0; i < n; ++i) {
    a[i] = 0.05 * (i - 199.5);
    b[i] = (i % 4 == 0 || i % 4 == 3) ? 0.5 : -0.5;
    for (int k = 0; k < D; ++k) Xp[static_cast<size_t>(i) * D + k] = 3.0 + a[i] * u[k] + (k == 2 ? b[i] : 0.0);
  }
  const std::vector<double> Y = an::pacmap_pca_init(Xp, n, D);
  ASSERT_EQ(Y.size(), static_cast<size_t>(2 * n));
  for (int i = 0; i < n; ++i) {
    // the largest component of u (2/3, first of the two) is made positive, so axis 1 = +u; axis 2 = +w
    EXPECT_NEAR(Y[2 * i], 0.01 * a[i], 1e-12);
    EXPECT_NEAR(Y[2 * i + 1], 0.01 * b[i], 1e-12);
  }
  // flipping the data flips nothing: the sign rule fixes each axis
  std::vector<double> Xm(Xp);
  for (double& x : Xm) x = -x;
  const std::vector<double> Ym = an::pacmap_pca_init(Xm, n, D);
  for (int i = 0; i < n; ++i) EXPECT_NEAR(Ym[2 * i], -0.01 * a[i], 1e-12);
}

TEST(Pacmap, JacobiEigenDecompositionSatisfiesAvEqualsLambdaV) {
  // a random symmetric 32×32 matrix (the descriptor's size) with two nearly equal eigenvalues built in: every
  // eigenpair satisfies A v = λ v, the vectors are orthonormal, and the eigenvalues are Eigen's
  const int D = 32;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  Eigen::MatrixXd B(D, D);
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) B(i, j) = g(rng);
  Eigen::MatrixXd A = B * B.transpose() / D;
  A(0, 0) += 1e-9;
  std::vector<double> a(static_cast<size_t>(D) * D);
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) a[static_cast<size_t>(i) * D + j] = 0.5 * (A(i, j) + A(j, i));
  std::vector<double> evals, evecs;
  an::symmetric_eigen(a, D, evals, evecs);
  ASSERT_EQ(evals.size(), static_cast<size_t>(D));
  const double scale = A.norm();
  for (int d = 0; d < D; ++d) {
    const Eigen::Map<const Eigen::VectorXd> v(evecs.data() + static_cast<size_t>(d) * D, D);
    EXPECT_NEAR(v.norm(), 1.0, 1e-13);
    EXPECT_LT((A * v - evals[d] * v).norm(), 1e-12 * scale) << "eigenpair " << d;
    for (int e = 0; e < d; ++e)
      EXPECT_NEAR(v.dot(Eigen::Map<const Eigen::VectorXd>(evecs.data() + static_cast<size_t>(e) * D, D)), 0.0, 1e-13);
  }
  std::vector<double> sorted(evals);
  std::sort(sorted.begin(), sorted.end());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A);
  for (int d = 0; d < D; ++d) EXPECT_NEAR(sorted[d], es.eigenvalues()[d], 1e-12 * scale);
  // and it is a function of its input: the same matrix twice gives the same bits
  std::vector<double> evals2, evecs2;
  an::symmetric_eigen(a, D, evals2, evecs2);
  EXPECT_EQ(evals, evals2);
  EXPECT_EQ(evecs, evecs2);
}

// ---- §4.1 item 4: integer-cell occupancy ---------------------------------------------------------------

TEST(Pacmap, ClassifyCellsRoundsHalfToEven) {
  // nearbyint: 0.5 → 0, 1.5 → 2, 2.5 → 2, −0.5 → −0; so states 0 and 3 share cell (0, 0) and states 1
  // and 2 share cell (2, 0)
  const std::vector<double> y = {0.5, 0.0, 1.5, 0.0, 2.5, 0.4, -0.5, 0.0, 7.2, -3.6};
  const std::vector<uint8_t> label = {0, 1, 0, 0, 1};
  const an::Occupancy o = an::classify_cells(y, label);
  EXPECT_EQ(o.cells_both, 1);
  EXPECT_EQ(o.states_both, 2);
  EXPECT_EQ(o.cells_train_only, 1);
  EXPECT_EQ(o.states_train_only, 2);
  EXPECT_EQ(o.cells_novel_only, 1);
  EXPECT_EQ(o.states_novel_only, 1);
  EXPECT_THROW(an::classify_cells(y, {0, 1, 2, 0, 0}), InputError);
  EXPECT_THROW(an::classify_cells(y, {0, 1}), InputError);
}

TEST(Pacmap, OccupancyOfSeparatedBlobsSharesNoCell) {
  const Data d = two_blobs(300, 6);
  an::PacmapOptions o;
  o.seed = 6;
  const an::Occupancy occ = an::classify_cells(an::pacmap_fit(d.X.data(), d.n, d.D, o), d.label);
  std::printf("[pacmap] blobs A/B: %ld cells (%ld shared), states train-only %ld, novel-only %ld\n",
              occ.cells_both + occ.cells_train_only + occ.cells_novel_only, occ.cells_both, occ.states_train_only,
              occ.states_novel_only);
  EXPECT_EQ(occ.cells_both, 0);
  EXPECT_EQ(occ.states_both, 0);
  EXPECT_EQ(occ.states_train_only, 300);
  EXPECT_EQ(occ.states_novel_only, 300);
}

TEST(Pacmap, OccupancyOfOneDistributionWithRandomLabelsIsMostlyShared) {
  const int n = 1000;
  Rng rng = divcoll::make_rng(8, 106, 0);
  std::vector<double> X(static_cast<size_t>(n) * kD);
  for (double& x : X) x = divcoll::normal(rng);
  std::vector<uint8_t> label(n);
  for (auto& l : label) l = static_cast<uint8_t>(divcoll::uniform_int(rng, 2));
  an::PacmapOptions o;
  o.seed = 8;
  const an::Occupancy occ = an::classify_cells(an::pacmap_fit(X.data(), n, kD, o), label);
  const long cells = occ.cells_both + occ.cells_train_only + occ.cells_novel_only;
  const double shared = static_cast<double>(occ.states_both) / n;
  std::printf("[pacmap] random labels: %ld of %ld cells shared, holding %.1f%% of states\n", occ.cells_both, cells,
              100 * shared);
  EXPECT_GT(shared, 0.8);
}

// ---- determinism, bad input, runtime --------------------------------------------------------------------

TEST(Pacmap, SameSeedGivesBitIdenticalOutput) {
  const Data d = two_blobs(150, 10);
  an::PacmapOptions o;
  o.seed = 42;
  const std::vector<double> a = an::pacmap_fit(d.X.data(), d.n, d.D, o);
  const std::vector<double> b = an::pacmap_fit(d.X.data(), d.n, d.D, o);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
  o.seed = 43;
  const std::vector<double> c = an::pacmap_fit(d.X.data(), d.n, d.D, o);
  EXPECT_NE(std::memcmp(a.data(), c.data(), a.size() * sizeof(double)), 0) << "the seed drives MN/FP sampling";
}

TEST(Pacmap, RejectsBadInput) {
  Rng rng = divcoll::make_rng(11, 107, 0);
  std::vector<double> X(50 * 101);
  for (double& x : X) x = divcoll::normal(rng);
  // the message of a refused input, or "" when it was accepted
  const auto message = [](auto&& f) -> std::string {
    try {
      f();
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  const std::string too_wide = message([&] { an::pacmap_fit(X.data(), 50, 101, {}); });
  EXPECT_NE(too_wide.find("D <= 100"), std::string::npos) << too_wide;
  EXPECT_NE(message([&] { an::pacmap_fit(X.data(), 3, 8, {}); }).find("at least 4"), std::string::npos);
  EXPECT_NE(message([&] { an::pacmap_fit(X.data(), 50, 1, {}); }).find("at least 2"), std::string::npos);
  EXPECT_THROW(an::pacmap_fit(nullptr, 50, 8, {}), InputError);
  std::vector<double> bad(X.begin(), X.begin() + 50 * 8);
  bad[17] = std::numeric_limits<double>::quiet_NaN();
  const std::string nan = message([&] { an::pacmap_fit(bad.data(), 50, 8, {}); });
  EXPECT_NE(nan.find("non-finite"), std::string::npos) << nan;
  EXPECT_NE(nan.find("row 2, column 1"), std::string::npos) << nan;
  bad[17] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(an::pacmap_fit(bad.data(), 50, 8, {}), InputError);
  EXPECT_THROW(an::pacmap_preprocess(bad.data(), 50, 8), InputError);
  // invalid options
  an::PacmapOptions o;
  o.lr = 0;
  EXPECT_THROW(an::pacmap_fit(X.data(), 50, 8, o), InputError);
  o = {};
  o.n_neighbors = 0;
  EXPECT_THROW(an::pacmap_fit(X.data(), 50, 8, o), InputError);
  o = {};
  o.phase_iters[2] = -1;
  EXPECT_THROW(an::pacmap_fit(X.data(), 50, 8, o), InputError);
  o = {};
  o.fp_ratio = 0.01;  // round(10 · 0.01) = 0 further pairs: the library refuses this too
  EXPECT_THROW(an::pacmap_fit(X.data(), 50, 8, o), InputError);
}

TEST(Pacmap, WallTimeOfOneFitWithN3000) {
  const Data d = two_blobs(1500, 12);
  an::PacmapOptions o;
  o.seed = 12;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<double> Xp = an::pacmap_preprocess(d.X.data(), d.n, d.D);
  const an::PacmapPairs p = an::pacmap_pairs(Xp, d.n, d.D, o);
  const auto t1 = std::chrono::steady_clock::now();
  const std::vector<double> Y = an::pacmap_fit(d.X.data(), d.n, d.D, o);
  const auto t2 = std::chrono::steady_clock::now();
  const double pairs_s = std::chrono::duration<double>(t1 - t0).count();
  const double fit_s = std::chrono::duration<double>(t2 - t1).count();
  double lo = 0, hi = 0;
  for (double v : Y) lo = std::min(lo, v), hi = std::max(hi, v);
  std::printf("[pacmap] n = 3000, D = 32: whole fit %.3f s (preprocess + pairs alone %.3f s); Y in [%.1f, %.1f]\n",
              fit_s, pairs_s, lo, hi);
  EXPECT_TRUE(all_finite(Y));
  EXPECT_EQ(p.nn.size(), 30000u);
}

}  // namespace
