// PaCMAP, step by step as in ANALYSIS.md §1 (reference: the Python library v0.9.1, pacmap.py). The
// deviations from the library are listed in pacmap.hpp; the small-n guards the library lacks are
// commented where they act (σ with fewer than 6 candidates, MN draws from fewer than 6 points).
#include "analysis/pacmap.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numeric>

#include "common/check.hpp"
#include "common/dmath.hpp"
#include "common/rng.hpp"

namespace divcoll::analysis {
namespace {

using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// seed_for stages of the two samplers: each has its own stream, so the FP pairs do not depend on how
// many draws the MN sampler made
constexpr uint64_t kStreamMN = 1;
constexpr uint64_t kStreamFP = 2;

// ---- input checks -------------------------------------------------------------------------------

void check_shape(int n, int D) {
  DIVCOLL_THROW_UNLESS(D <= 100, "pacmap: the input has D = " << D
                                     << " columns, but only D <= 100 is supported (the reference library's "
                                        "D > 100 path, a TruncatedSVD to 100 components, is not implemented)");
  DIVCOLL_THROW_UNLESS(D >= 2, "pacmap: the input has D = " << D
                                   << " columns, but a 2-D embedding needs at least 2 input dimensions");
  DIVCOLL_THROW_UNLESS(n >= 4, "pacmap: the input has n = " << n << " points, but at least 4 are needed");
}

void check_finite(const double* X, int n, int D, const char* what) {
  const size_t N = static_cast<size_t>(n) * D;
  for (size_t q = 0; q < N; ++q)
    DIVCOLL_THROW_UNLESS(std::isfinite(X[q]), "pacmap: " << what << " has a non-finite value (" << X[q]
                                                         << ") at row " << q / D << ", column " << q % D);
}

void check_options(const PacmapOptions& o) {
  DIVCOLL_THROW_UNLESS(o.n_neighbors >= 1, "pacmap: n_neighbors must be at least 1, not " << o.n_neighbors);
  DIVCOLL_THROW_UNLESS(std::isfinite(o.mn_ratio) && o.mn_ratio >= 0,
                       "pacmap: mn_ratio must be finite and >= 0, not " << o.mn_ratio);
  DIVCOLL_THROW_UNLESS(std::isfinite(o.fp_ratio) && o.fp_ratio > 0,
                       "pacmap: fp_ratio must be finite and > 0, not " << o.fp_ratio);
  DIVCOLL_THROW_UNLESS(std::isfinite(o.lr) && o.lr > 0, "pacmap: lr must be finite and > 0, not " << o.lr);
  for (int p = 0; p < 3; ++p)
    DIVCOLL_THROW_UNLESS(o.phase_iters[p] >= 0,
                         "pacmap: phase_iters[" << p << "] must be >= 0, not " << o.phase_iters[p]);
}

// ---- §1.1 pair counts ---------------------------------------------------------------------------

struct Counts {
  int nn, mn, fp, extra;  // pairs per point of each kind, kNN candidates per point
};

// §1.1: n_MN, n_FP from the requested n_NB (Python's round is half-to-even, like nearbyint), then the
// library's small-n guards (decide_num_pairs)
Counts pair_counts(int n, const PacmapOptions& o) {
  const auto rounded = [n](double x) { return x >= n ? n : static_cast<int>(std::nearbyint(x)); };
  int nn = o.n_neighbors;
  int mn = rounded(nn * o.mn_ratio);
  int fp = rounded(nn * o.fp_ratio);
  nn = std::min(nn, n - 1);
  fp = std::min(fp, n - 1 - nn);
  mn = std::min(mn, n - 1);
  // too many pairs for n points: rescale to int(n/3.5)·(1, MN_ratio, FP_ratio), i.e. (1, 0.5, 2) at the
  // defaults (unchanged for n >= 36); the two clamps again keep the rejection samplers finite
  if (nn + mn + fp >= n) {
    const int k = static_cast<int>(n / 3.5);
    nn = k;
    mn = std::min(static_cast<int>(k * o.mn_ratio), n - 1);
    fp = std::min(static_cast<int>(k * o.fp_ratio), n - 1 - nn);
  }
  DIVCOLL_THROW_UNLESS(nn >= 1, "pacmap: with n = " << n << " points the number of nearest neighbours drops below 1");
  DIVCOLL_THROW_UNLESS(fp >= 1, "pacmap: with n = " << n << " points and fp_ratio = " << o.fp_ratio
                                                    << " the number of further pairs drops below 1");
  return {nn, mn, fp, std::min(nn + 50, n - 1)};
}

// ---- §1.3 step 1: exact kNN -----------------------------------------------------------------------

// squared Euclidean distance of rows i and j, summed in d order (no reassociation: the same bits on
// every machine)
inline double sqdist(const double* Xp, int D, int i, int j) {
  const double* a = Xp + static_cast<size_t>(i) * D;
  const double* b = Xp + static_cast<size_t>(j) * D;
  double s = 0;
  for (int d = 0; d < D; ++d) {
    const double diff = a[d] - b[d];
    s += diff * diff;
  }
  return s;
}

// the k nearest *other* points of every point, rows sorted by (distance, index); nbr and dist are n×k
// row-major. i is excluded by index, so exact duplicates are neighbours at distance 0 (the library asks
// for k+1 and drops the first, assuming it is i).
// Deviation from the library (approximate faiss/Annoy): exact brute force, in two stages.
//  1. preselection: key_j = ‖x_j‖² − 2 x_i·x_j (= ‖x_i − x_j‖² − ‖x_i‖²) by Eigen products of a block of
//     rows with a block of columns (sized to stay in cache), keeping per row the h = k + kSpare smallest
//     keys;
//  2. every j with key_j <= (k-th smallest key) + tol, tol a bound on twice the rounding error of a key,
//     gets its distance recomputed directly (sqdist), and the k smallest by (distance, index) are kept.
// A point among the true k nearest has key_j <= k-th key + tol, so stage 2 sees all of them: the result
// is the exact kNN and does not depend on the products' rounding (which varies with Eigen's
// cache-size-dependent blocking). When the h-th smallest key is itself within the cut (more than
// kSpare keys crowd at the k-th place, e.g. a big cluster of duplicates), all n distances of that row
// are computed directly instead.
void exact_knn(const std::vector<double>& Xp, int n, int D, int k, std::vector<int>& nbr, std::vector<double>& dist) {
  const Eigen::Map<const RowMat> X(Xp.data(), n, D);
  const Eigen::VectorXd sq = X.rowwise().squaredNorm();
  const double* sqp = sq.data();
  const double sq_max = sq.maxCoeff();
  const double eps = std::numeric_limits<double>::epsilon();
  nbr.resize(static_cast<size_t>(n) * k);
  dist.resize(static_cast<size_t>(n) * k);
  constexpr int kSpare = 8, kRows = 64, kCols = 512;
  const int h = std::min(k + kSpare, n - 1);
  const int cap = 8 * h;
  using Entry = std::pair<double, int>;  // (key, j), ordered by (key, j)
  std::vector<Entry> bufs(static_cast<size_t>(kRows) * cap);
  std::vector<int> count(kRows);
  std::vector<double> thresh(kRows), kth(h), keyrow(kCols);
  std::vector<Entry> cand;               // (exact distance, j) of stage 2
  RowMat G(kRows, kCols);
  for (int r0 = 0; r0 < n; r0 += kRows) {
    const int b = std::min(kRows, n - r0);
    std::fill(count.begin(), count.end(), 0);
    std::fill(thresh.begin(), thresh.end(), std::numeric_limits<double>::infinity());
    // stage 1, one column block at a time, in ascending j. Each row keeps a buffer of candidates below
    // its threshold; a full buffer is cut to its h smallest by nth_element, and the threshold becomes
    // the h-th smallest key. A later j with an equal key has a larger index than every kept one, so
    // "key < threshold" keeps exactly the h smallest by (key, j).
    for (int c0 = 0; c0 < n; c0 += kCols) {
      const int cols = std::min(kCols, n - c0);
      G.topLeftCorner(b, cols).noalias() = X.middleRows(r0, b) * X.middleRows(c0, cols).transpose();
      for (int ii = 0; ii < b; ++ii) {
        const int i = r0 + ii;
        Entry* buf = bufs.data() + static_cast<size_t>(ii) * cap;
        const double* g = G.data() + static_cast<size_t>(ii) * kCols;
        int m = count[ii];
        double w = thresh[ii];
        // the keys of this row block (a vectorized loop), then a scan that rarely branches
        for (int c = 0; c < cols; ++c) keyrow[c] = sqp[c0 + c] - 2.0 * g[c];
        for (int c = 0; c < cols; ++c) {
          if (keyrow[c] < w && c0 + c != i) {
            buf[m++] = {keyrow[c], c0 + c};
            if (m == cap) {
              std::nth_element(buf, buf + (h - 1), buf + cap);
              m = h;
              w = buf[h - 1].first;
            }
          }
        }
        count[ii] = m;
        thresh[ii] = w;
      }
    }
    // stage 2
    for (int ii = 0; ii < b; ++ii) {
      const int i = r0 + ii;
      Entry* buf = bufs.data() + static_cast<size_t>(ii) * cap;
      // the h smallest of the n − 1 keys (at least h were kept), the largest of them last
      std::nth_element(buf, buf + (h - 1), buf + count[ii]);
      const double hth_key = buf[h - 1].first;
      for (int c = 0; c < h; ++c) kth[c] = buf[c].first;
      std::nth_element(kth.begin(), kth.begin() + (k - 1), kth.end());
      // a key sums D products of entries bounded by √sq_i and √sq_max, plus sq_j: its rounding error is
      // well below half of this tol
      const double tol = 8.0 * D * eps * (sq_max + std::sqrt(sqp[i] * sq_max)) + 4.0 * eps * std::abs(kth[k - 1]);
      const double cut = kth[k - 1] + tol;
      cand.clear();
      if (h == n - 1 || hth_key > cut) {
        // every key not kept is >= the h-th smallest > cut
        for (int c = 0; c < h; ++c)
          if (buf[c].first <= cut) cand.emplace_back(std::sqrt(sqdist(Xp.data(), D, i, buf[c].second)), buf[c].second);
      } else {
        for (int j = 0; j < n; ++j)
          if (j != i) cand.emplace_back(std::sqrt(sqdist(Xp.data(), D, i, j)), j);
      }
      std::partial_sort(cand.begin(), cand.begin() + k, cand.end());
      for (int c = 0; c < k; ++c) {
        nbr[static_cast<size_t>(i) * k + c] = cand[c].second;
        dist[static_cast<size_t>(i) * k + c] = cand[c].first;
      }
    }
  }
}

// ---- §1.7 coefficients (the library's operation order) --------------------------------------------

inline double coef_nn(double dt, double w) { return w * (20.0 / ((10.0 + dt) * (10.0 + dt))); }
inline double coef_mn(double dt, double w) { return w * 20000.0 / ((10000.0 + dt) * (10000.0 + dt)); }
inline double coef_fp(double dt, double w) { return -(w * 2.0 / ((1.0 + dt) * (1.0 + dt))); }

// §1.7: add the gradient of one pair type into g (n×2): c·y_ij to i, −c·y_ij to j; allocates nothing
template <double (*Coef)(double, double)>
inline void accumulate(const std::vector<std::pair<int, int>>& pairs, double w, const double* y, double* g) {
  for (const auto& [i, j] : pairs) {
    const double dx = y[2 * i] - y[2 * j];
    const double dy = y[2 * i + 1] - y[2 * j + 1];
    const double c = Coef(1.0 + dx * dx + dy * dy, w);
    g[2 * i] += c * dx;
    g[2 * i + 1] += c * dy;
    g[2 * j] -= c * dx;
    g[2 * j + 1] -= c * dy;
  }
}

}  // namespace

// ---- §1.8 -----------------------------------------------------------------------------------------

// §1.8 find_weight: phase 1 ramps w_MN linearly from 1000 (t = 0) towards 3, dividing by P1 itself
PacmapWeights pacmap_weights(int t, const PacmapOptions& o) {
  const int p1 = o.phase_iters[0], p2 = o.phase_iters[1];
  if (t < p1) {
    const double a = static_cast<double>(t) / p1;
    return {(1.0 - a) * 1000.0 + a * 3.0, 2.0, 1.0};
  }
  if (t < p1 + p2) return {3.0, 3.0, 1.0};
  return {0.0, 1.0, 1.0};
}

// ---- §1.2 -----------------------------------------------------------------------------------------

// §1.2, D <= 100 path: subtract the global min, divide by the global max of the shifted matrix (v0.9.1;
// up to 0.8.0 the max of the original X, §1.11), subtract the column means. When all entries are equal
// the max is 0 and the library would divide 0/0; here the division is skipped.
std::vector<double> pacmap_preprocess(const double* X, int n, int D) {
  DIVCOLL_THROW_UNLESS(X != nullptr, "pacmap: the input matrix is null");
  check_shape(n, D);
  check_finite(X, n, D, "the input");
  const size_t N = static_cast<size_t>(n) * D;
  std::vector<double> Xp(X, X + N);
  const double mn = *std::min_element(Xp.begin(), Xp.end());
  for (double& x : Xp) x -= mn;
  const double mx = *std::max_element(Xp.begin(), Xp.end());
  if (mx > 0)
    for (double& x : Xp) x /= mx;
  std::vector<double> mu(D, 0.0);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < D; ++d) mu[d] += Xp[static_cast<size_t>(i) * D + d];
  for (double& m : mu) m /= n;
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < D; ++d) Xp[static_cast<size_t>(i) * D + d] -= mu[d];
  // a finite input whose range overflows a double (e.g. ±1e308) would become inf here
  check_finite(Xp.data(), n, D, "the input, after shifting by its minimum,");
  return Xp;
}

// ---- §1.3–1.5 -------------------------------------------------------------------------------------

// §1.3 NN pairs (σ-scaled distances over the n_extra exact neighbours), §1.4 MN pairs (2nd-nearest of 6
// distinct draws), §1.5 FP pairs (distinct draws outside i's NN pairs); counts from §1.1's guards.
// Deviation: draws come from divcoll::Rng streams seed_for(o.seed, 1 (MN) / 2 (FP), 0), one per sampler.
PacmapPairs pacmap_pairs(const std::vector<double>& Xp, int n, int D, const PacmapOptions& o) {
  check_options(o);
  check_shape(n, D);
  DIVCOLL_THROW_UNLESS(Xp.size() == static_cast<size_t>(n) * D,
                       "pacmap: the data has " << Xp.size() << " values, not n·D = " << n << "·" << D);
  check_finite(Xp.data(), n, D, "the preprocessed input");
  const Counts c = pair_counts(n, o);
  const int k = c.extra;

  // §1.3 step 1: the k nearest other points
  std::vector<int> nbr;
  std::vector<double> r;
  exact_knn(Xp, n, D, k, nbr, r);

  // §1.3 step 2: σ_i = mean distance to the 4th–6th neighbours, floored at 1e-10. Small-n guard: with
  // k < 6 candidates the mean runs over those of the 4th–6th that exist (as numpy's slice 3:6 does), and
  // with k <= 3 (where numpy would give NaN) σ_i is the distance to the farthest candidate.
  std::vector<double> sigma(n);
  for (int i = 0; i < n; ++i) {
    const double* ri = r.data() + static_cast<size_t>(i) * k;
    const int lo = 3, hi = std::min(6, k);
    double s;
    if (hi > lo) {
      s = 0;
      for (int t = lo; t < hi; ++t) s += ri[t];
      s /= (hi - lo);
    } else {
      s = ri[k - 1];
    }
    sigma[i] = std::max(s, 1e-10);
  }

  // §1.3 steps 3–4: s_ij = r² / σ_i / σ_j (the library's order), keep the n_NB smallest (ties: nearer first)
  PacmapPairs p;
  p.nn.reserve(static_cast<size_t>(n) * c.nn);
  std::vector<double> scaled(k);
  std::vector<int> order(k);
  for (int i = 0; i < n; ++i) {
    const int* ni = nbr.data() + static_cast<size_t>(i) * k;
    const double* ri = r.data() + static_cast<size_t>(i) * k;
    for (int t = 0; t < k; ++t) scaled[t] = ri[t] * ri[t] / sigma[i] / sigma[ni[t]];
    std::iota(order.begin(), order.end(), 0);
    std::partial_sort(order.begin(), order.begin() + c.nn, order.end(), [&](int a, int b) {
      return scaled[a] < scaled[b] || (scaled[a] == scaled[b] && a < b);
    });
    for (int t = 0; t < c.nn; ++t) p.nn.emplace_back(i, ni[order[t]]);
  }

  // §1.4 MN pairs: per round, 6 distinct uniform draws rejecting i and i's earlier MN partners; the
  // partner is the 2nd-nearest of the 6 (first occurrence wins ties, like np.argmin). Small-n guard:
  // when fewer than 6 points are eligible, all eligible ones are drawn (the library would loop forever),
  // and a single eligible point is taken as it is.
  {
    Rng rng = make_rng(o.seed, kStreamMN, 0);
    p.mn.reserve(static_cast<size_t>(n) * c.mn);
    int cand[6];
    double cd[6];
    for (int i = 0; i < n; ++i) {
      const size_t first = p.mn.size();
      for (int round = 0; round < c.mn; ++round) {
        const int m = std::min(6, n - 1 - round);
        for (int q = 0; q < m; ++q) {
          int j;
          for (;;) {
            j = static_cast<int>(uniform_int(rng, static_cast<uint64_t>(n)));
            if (j == i) continue;
            bool taken = false;
            for (int u = 0; u < q && !taken; ++u) taken = cand[u] == j;
            for (size_t u = first; u < p.mn.size() && !taken; ++u) taken = p.mn[u].second == j;
            if (!taken) break;
          }
          cand[q] = j;
          cd[q] = sqdist(Xp.data(), D, i, j);
        }
        int pick = 0;
        if (m >= 2) {
          const int a = static_cast<int>(std::min_element(cd, cd + m) - cd);
          pick = -1;
          for (int q = 0; q < m; ++q)
            if (q != a && (pick < 0 || cd[q] < cd[pick])) pick = q;
        }
        p.mn.emplace_back(i, cand[pick]);
      }
    }
  }

  // §1.5 FP pairs: n_FP distinct uniform draws rejecting i and i's n_NB NN partners (no distance test)
  {
    Rng rng = make_rng(o.seed, kStreamFP, 0);
    p.fp.reserve(static_cast<size_t>(n) * c.fp);
    for (int i = 0; i < n; ++i) {
      const auto nn_begin = p.nn.begin() + static_cast<ptrdiff_t>(i) * c.nn;
      const size_t first = p.fp.size();
      for (int q = 0; q < c.fp; ++q) {
        int j;
        for (;;) {
          j = static_cast<int>(uniform_int(rng, static_cast<uint64_t>(n)));
          if (j == i) continue;
          bool taken = false;
          for (size_t u = first; u < p.fp.size() && !taken; ++u) taken = p.fp[u].second == j;
          for (int u = 0; u < c.nn && !taken; ++u) taken = nn_begin[u].second == j;
          if (!taken) break;
        }
        p.fp.emplace_back(i, j);
      }
    }
  }
  return p;
}

// ---- §1.6 -----------------------------------------------------------------------------------------

// the eigenvalues and eigenvectors of the symmetric D×D matrix A (row-major) by cyclic Jacobi rotations
// (Golub & Van Loan, Matrix Computations, §8.5): evals[d] and eigenvector d at evecs[d·D, (d+1)·D).
// Why not Eigen's SelfAdjointEigenSolver: its tridiagonalisation sums in an order set by the vector width of the
// instruction set it was compiled for, so its eigenvectors, PaCMAP's init and so its embedding differed in the last
// bits between an AVX-512, an AVX2 and a baseline build. Every operation here is a scalar IEEE operation in a fixed
// order (no fused multiply-adds: -ffp-contract=off), so the result is the same bits on every CPU. D is small (the
// descriptor's 32): a sweep is D²/2 rotations of O(D), and a few sweeps converge.
void symmetric_eigen(std::vector<double> A, int D, std::vector<double>& evals, std::vector<double>& evecs) {
  auto at = [&](int i, int j) -> double& { return A[static_cast<size_t>(i) * D + j]; };
  std::vector<double> V(static_cast<size_t>(D) * D, 0.0);  // columns are the eigenvectors (row-major)
  for (int d = 0; d < D; ++d) V[static_cast<size_t>(d) * D + d] = 1.0;
  double total = 0;
  for (double a : A) total += a * a;
  constexpr int kMaxSweeps = 100;
  int sweep = 0;
  for (; sweep < kMaxSweeps; ++sweep) {
    double off = 0;
    for (int p = 0; p < D; ++p)
      for (int q = p + 1; q < D; ++q) off += at(p, q) * at(p, q);
    if (off <= 1e-30 * total) break;  // (1e-15 of the norm, squared)
    for (int p = 0; p < D - 1; ++p) {
      for (int q = p + 1; q < D; ++q) {
        const double apq = at(p, q);
        if (apq == 0) continue;
        // the rotation that zeroes A(p, q): t = tan θ, the smaller root of t² + 2τt − 1 = 0
        const double tau = (at(q, q) - at(p, p)) / (2.0 * apq);
        const double t = (tau >= 0 ? 1.0 : -1.0) / (std::abs(tau) + std::sqrt(1.0 + tau * tau));
        const double c = 1.0 / std::sqrt(1.0 + t * t);
        const double s = t * c;
        for (int k = 0; k < D; ++k) {  // A ← A J (columns p, q)
          const double akp = at(k, p), akq = at(k, q);
          at(k, p) = c * akp - s * akq;
          at(k, q) = s * akp + c * akq;
        }
        for (int k = 0; k < D; ++k) {  // A ← Jᵀ A (rows p, q)
          const double apk = at(p, k), aqk = at(q, k);
          at(p, k) = c * apk - s * aqk;
          at(q, k) = s * apk + c * aqk;
        }
        at(p, q) = at(q, p) = 0.0;
        for (int k = 0; k < D; ++k) {  // V ← V J
          double* row = V.data() + static_cast<size_t>(k) * D;
          const double vkp = row[p], vkq = row[q];
          row[p] = c * vkp - s * vkq;
          row[q] = s * vkp + c * vkq;
        }
      }
    }
  }
  DIVCOLL_THROW_UNLESS(sweep < kMaxSweeps, "pacmap: the eigen-decomposition of the covariance did not converge in "
                                               << kMaxSweeps << " Jacobi sweeps");
  evals.resize(D);
  evecs.resize(static_cast<size_t>(D) * D);
  for (int d = 0; d < D; ++d) {
    evals[d] = at(d, d);
    for (int k = 0; k < D; ++k) evecs[static_cast<size_t>(d) * D + k] = V[static_cast<size_t>(k) * D + d];
  }
}

// §1.6: Y⁰ = 0.01 × (X − mean)·[v₁ v₂], v₁, v₂ the top-2 eigenvectors of the D×D covariance (= sklearn
// PCA's top right singular vectors), each signed so that its largest-|component| entry (first on ties)
// is positive, which is sklearn's svd_flip on V
std::vector<double> pacmap_pca_init(const std::vector<double>& Xp, int n, int D) {
  check_shape(n, D);
  DIVCOLL_THROW_UNLESS(Xp.size() == static_cast<size_t>(n) * D,
                       "pacmap: the data has " << Xp.size() << " values, not n·D = " << n << "·" << D);
  check_finite(Xp.data(), n, D, "the preprocessed input");
  // column means and the covariance, summed in row order with plain loops (Eigen's products block by
  // the cache size of the machine, which would change the rounding, and the init, from one CPU to another)
  std::vector<double> mu(D, 0.0);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < D; ++d) mu[d] += Xp[static_cast<size_t>(i) * D + d];
  for (double& m : mu) m /= n;
  std::vector<double> xc(D);
  std::vector<double> C(static_cast<size_t>(D) * D, 0.0);  // row-major; upper triangle accumulated, then mirrored
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < D; ++d) xc[d] = Xp[static_cast<size_t>(i) * D + d] - mu[d];
    for (int a = 0; a < D; ++a)
      for (int b = a; b < D; ++b) C[static_cast<size_t>(a) * D + b] += xc[a] * xc[b];
  }
  for (int a = 0; a < D; ++a)
    for (int b = a; b < D; ++b)
      C[static_cast<size_t>(b) * D + a] = C[static_cast<size_t>(a) * D + b] = C[static_cast<size_t>(a) * D + b] / (n - 1);
  std::vector<double> evals, evecs;
  symmetric_eigen(C, D, evals, evecs);
  // the two largest eigenvalues (the first index on ties)
  int top[2] = {-1, -1};
  for (int a = 0; a < 2; ++a)
    for (int d = 0; d < D; ++d)
      if (d != top[0] && (top[a] < 0 || evals[d] > evals[top[a]])) top[a] = d;
  std::vector<double> V(2 * static_cast<size_t>(D));  // axis a at [a·D, (a+1)·D)
  for (int a = 0; a < 2; ++a) {
    const double* v = evecs.data() + static_cast<size_t>(top[a]) * D;
    int big = 0;
    for (int d = 1; d < D; ++d)
      if (std::abs(v[d]) > std::abs(v[big])) big = d;
    const double sign = v[big] < 0 ? -1.0 : 1.0;
    for (int d = 0; d < D; ++d) V[static_cast<size_t>(a) * D + d] = sign * v[d];
  }
  std::vector<double> y(static_cast<size_t>(n) * 2);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 2; ++a) {
      double s = 0;
      for (int d = 0; d < D; ++d) s += (Xp[static_cast<size_t>(i) * D + d] - mu[d]) * V[static_cast<size_t>(a) * D + d];
      y[2 * static_cast<size_t>(i) + a] = 0.01 * s;
    }
  }
  return y;
}

// ---- §1.7 -----------------------------------------------------------------------------------------

// §1.7: NN 20w/(10+d̃)², MN 20000w/(10000+d̃)², FP −2w/(1+d̃)²
double pacmap_coefficient(char type, double d_tilde, double w) {
  switch (type) {
    case 'n': return coef_nn(d_tilde, w);
    case 'm': return coef_mn(d_tilde, w);
    case 'f': return coef_fp(d_tilde, w);
    default: break;
  }
  throw InputError(msg() << "pacmap: unknown pair type '" << type << "' (expected 'n', 'm' or 'f')");
}

// ---- §1.9 -----------------------------------------------------------------------------------------

// §1.9 Adam (β1 = 0.9, β2 = 0.999, ε = 1e-7 added to √v): bias corrections folded into lr_t, exactly as
// the library's update_embedding_adam
void pacmap_adam_step(std::vector<double>& y, const std::vector<double>& g, AdamState& s, int t, double lr) {
  const size_t N = y.size();
  DIVCOLL_THROW_UNLESS(g.size() == N, "pacmap: the gradient has " << g.size() << " values, y has " << N);
  DIVCOLL_THROW_UNLESS(t >= 0, "pacmap: the Adam iteration index must be >= 0, not " << t);
  if (s.m.empty() && s.v.empty()) {
    s.m.assign(N, 0.0);
    s.v.assign(N, 0.0);
  }
  DIVCOLL_THROW_UNLESS(s.m.size() == N && s.v.size() == N, "pacmap: the Adam state does not match y in size");
  constexpr double beta1 = 0.9, beta2 = 0.999, eps = 1e-7;
  const double lr_t = lr * std::sqrt(1.0 - dmath::pow(beta2, t + 1)) / (1.0 - dmath::pow(beta1, t + 1));
  for (size_t q = 0; q < N; ++q) {
    s.m[q] += (1.0 - beta1) * (g[q] - s.m[q]);
    s.v[q] += (1.0 - beta2) * (g[q] * g[q] - s.v[q]);
    y[q] -= lr_t * s.m[q] / (std::sqrt(s.v[q]) + eps);
  }
}

// ---- the whole fit --------------------------------------------------------------------------------

// §1.2 → §1.3–1.5 → §1.6 → 450 full-batch iterations of §1.7 gradients with §1.8 weights and §1.9 Adam.
// Y is returned as is (no rescaling or centring).
std::vector<double> pacmap_fit(const double* X, int n, int D, const PacmapOptions& o) {
  check_options(o);
  const std::vector<double> Xp = pacmap_preprocess(X, n, D);
  const PacmapPairs p = pacmap_pairs(Xp, n, D, o);
  std::vector<double> y = pacmap_pca_init(Xp, n, D);
  std::vector<double> g(y.size());
  AdamState s;
  s.m.assign(y.size(), 0.0);
  s.v.assign(y.size(), 0.0);
  const int iters = o.phase_iters[0] + o.phase_iters[1] + o.phase_iters[2];
  for (int t = 0; t < iters; ++t) {
    const PacmapWeights w = pacmap_weights(t, o);
    std::fill(g.begin(), g.end(), 0.0);
    // the library's order: NN, MN, FP (MN adds exactly zero when w_MN = 0, so it is skipped then)
    accumulate<coef_nn>(p.nn, w.w_nn, y.data(), g.data());
    if (w.w_mn != 0.0) accumulate<coef_mn>(p.mn, w.w_mn, y.data(), g.data());
    accumulate<coef_fp>(p.fp, w.w_fp, y.data(), g.data());
    pacmap_adam_step(y, g, s, t, o.lr);
  }
  return y;
}

// ---- §1.12 ----------------------------------------------------------------------------------------

// §1.12: cells of the integer grid (half-to-even rounding, as np.rint), each classed by which labels
// occur in it; states are counted under their cell's class
Occupancy classify_cells(const std::vector<double>& y, const std::vector<uint8_t>& label) {
  DIVCOLL_THROW_UNLESS(y.size() == 2 * label.size(), "classify_cells: y has " << y.size() << " values for "
                                                                              << label.size() << " labels");
  struct Key {
    long long ix, iy;
    uint8_t label;
  };
  std::vector<Key> keys(label.size());
  for (size_t i = 0; i < label.size(); ++i) {
    DIVCOLL_THROW_UNLESS(label[i] <= 1, "classify_cells: label " << int(label[i]) << " of state " << i
                                                                 << " is neither 0 (train) nor 1 (novel)");
    for (int a = 0; a < 2; ++a)
      DIVCOLL_THROW_UNLESS(std::isfinite(y[2 * i + a]) && std::abs(y[2 * i + a]) < 1e15,
                           "classify_cells: coordinate " << y[2 * i + a] << " of state " << i
                                                         << " is not finite or too large");
    keys[i] = {static_cast<long long>(std::nearbyint(y[2 * i])), static_cast<long long>(std::nearbyint(y[2 * i + 1])),
               label[i]};
  }
  std::sort(keys.begin(), keys.end(),
            [](const Key& a, const Key& b) { return a.ix < b.ix || (a.ix == b.ix && a.iy < b.iy); });
  Occupancy occ;
  for (size_t b = 0; b < keys.size();) {
    size_t e = b;
    unsigned seen = 0;
    while (e < keys.size() && keys[e].ix == keys[b].ix && keys[e].iy == keys[b].iy) seen |= 1u << keys[e++].label;
    const long count = static_cast<long>(e - b);
    if (seen == 3u) {
      ++occ.cells_both;
      occ.states_both += count;
    } else if (seen == 1u) {
      ++occ.cells_train_only;
      occ.states_train_only += count;
    } else {
      ++occ.cells_novel_only;
      occ.states_novel_only += count;
    }
    b = e;
  }
  return occ;
}

}  // namespace divcoll::analysis
