// PaCMAP (Wang, Huang, Rudin & Shaposhnik, JMLR 2021) for 2-D embeddings of hidden states, written to
// ANALYSIS.md §1, which reads the reference library v0.9.1 (`source/pacmap/pacmap.py`) step by step:
// preprocessing (§1.2), NN / MN / FP pairs (§1.3–1.5), PCA init (§1.6), the three losses (§1.7), the
// three-phase weights (§1.8), Adam (§1.9), and the integer-cell occupancy of the paper (§1.12).
//
// Deviations from the Python library, all deliberate:
//  - exact brute-force kNN, excluding i by index, instead of the approximate faiss/Annoy backend (which
//    also assumes that the first neighbour returned is i itself, wrong with exact duplicates);
//  - MN and FP pairs are drawn from divcoll::Rng seeded by PacmapOptions::seed, so one seed gives
//    bit-identical pairs and embedding; the library's numba sampler is nondeterministic without
//    random_state and uses numpy's generator with it, so no bit match with Python is possible;
//  - double precision throughout (the library works in float32);
//  - only D <= 100 (the library's D > 100 path, TruncatedSVD to 100 components, is not implemented);
//  - small-n guards that the library lacks, so it never loops forever or divides by zero (see pacmap.cpp).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace divcoll::analysis {

struct PacmapOptions {
  int n_neighbors = 10;                 // n_NB, NN pairs per point
  double mn_ratio = 0.5;                // n_MN = round(n_NB · mn_ratio) mid-near pairs per point
  double fp_ratio = 2.0;                // n_FP = round(n_NB · fp_ratio) further pairs per point
  double lr = 1.0;                      // Adam learning rate
  int phase_iters[3] = {100, 100, 250}; // iterations of the three weight phases (§1.8)
  uint64_t seed = 0;                    // seeds pair sampling (MN, FP) through divcoll::Rng
};

// directed pairs (i, j), row-major by i: i's pairs are entries [i·k, (i+1)·k) of each list
struct PacmapPairs {
  std::vector<std::pair<int, int>> nn, mn, fp;
};

struct PacmapWeights {
  double w_mn, w_nn, w_fp;
};

// §1.8 find_weight: the loss weights of (0-based) iteration t
PacmapWeights pacmap_weights(int t, const PacmapOptions& o = {});

// the whole fit. X: n rows × D columns, row-major. Returns Y, n×2 row-major (y[2i], y[2i+1]).
// @throws InputError when n < 4, D < 2, D > 100, any entry of X is not finite, or an option is invalid
std::vector<double> pacmap_fit(const double* X, int n, int D, const PacmapOptions& o = {});

// ---- the pieces, exposed for tests ----------------------------------------------------------------

// §1.2 (D <= 100 path): X − global min, / global max of the shifted matrix, − column means
std::vector<double> pacmap_preprocess(const double* X, int n, int D);

// §1.3–1.5 on the preprocessed data, with the small-n guards of §1.1
PacmapPairs pacmap_pairs(const std::vector<double>& Xp, int n, int D, const PacmapOptions& o);

// §1.6: 0.01 × the scores on the top-2 principal axes (n×2 row-major); each axis' sign makes its
// largest-|component| entry positive (sklearn's svd_flip on V)
std::vector<double> pacmap_pca_init(const std::vector<double>& Xp, int n, int D);

// the eigen-decomposition of a symmetric D×D matrix A (row-major) by cyclic Jacobi rotations, in the same bits on
// every CPU: evals[d] (unordered) and its unit eigenvector at evecs[d·D, (d+1)·D)
void symmetric_eigen(std::vector<double> A, int D, std::vector<double>& evals, std::vector<double>& evecs);

// §1.7: c with ∂L/∂y_i = c·(y_i − y_j) for one pair of type 'n' (NN), 'm' (MN) or 'f' (FP), where
// d_tilde = 1 + ‖y_i − y_j‖² and w is the pair type's weight
double pacmap_coefficient(char type, double d_tilde, double w);

// §1.9: one Adam update of y with gradient g at 0-based iteration t; empty m, v start at zero
struct AdamState {
  std::vector<double> m, v;
};
void pacmap_adam_step(std::vector<double>& y, const std::vector<double>& g, AdamState& s, int t, double lr);

// §1.12: round each coordinate half-to-even (std::nearbyint), cell = (ix, iy); label[i] is 0 (training
// environment) or 1 (novel). A cell is "both" when states of both labels fall in it; a state counts
// under its cell's class.
struct Occupancy {
  long states_both = 0, states_train_only = 0, states_novel_only = 0;
  long cells_both = 0, cells_train_only = 0, cells_novel_only = 0;
};
Occupancy classify_cells(const std::vector<double>& y, const std::vector<uint8_t>& label);

}  // namespace divcoll::analysis
