// dynamic time warping distance between two multivariate series (ANALYSIS.md §2), the measure of the DTW
// adversity of SPEC §8.1.
//
// Default variant (ANALYSIS.md's recommendation): symmetric1 steps (1,1), (1,0), (0,1), each adding the
// local cost c(i,j) once; Euclidean local cost ‖a_i − b_j‖₂; plain sum along the path. The length K of the
// optimal path is carried beside D, ties broken diagonal, vertical (i−1, j), horizontal (i, j−1), so that
// the per-step distance D/K (§2.4 (a)) is well defined. Options: the tslearn form √Σ‖·‖², the symmetric2
// step (diagonal costs 2c), and a Sakoe–Chiba band of radius r: |i − j| ≤ r when n = m; for n ≠ m slanted
// (§2.3), floor(c − r) ≤ j ≤ ceil(c + r) with c = i·(m−1)/(n−1), each row widened where needed so that the
// end cell stays reachable for every r ≥ 0. Memory O(m), two rolling rows for D and two for K.
#pragma once

namespace divcoll::analysis {

enum class DtwCost {
  euclidean,       // c = ‖a_i − b_j‖₂, distance = Σ c along the path (the default)
  squared_sqrt,    // c = ‖a_i − b_j‖², distance = √(Σ c) (tslearn, dtaidistance)
};

enum class DtwStep {
  symmetric1,  // D(i,j) = c + min(D(i−1,j−1), D(i−1,j), D(i,j−1))
  symmetric2,  // D(i,j) = min(D(i−1,j−1) + 2c, D(i−1,j) + c, D(i,j−1) + c); D(0,0) = c(0,0)
};

struct DtwOptions {
  int band = -1;  // Sakoe–Chiba radius r in frames (slanted when n ≠ m); < 0 = no band
  DtwCost cost = DtwCost::euclidean;
  DtwStep step = DtwStep::symmetric1;
};

struct DtwResult {
  double distance;  // D(n−1, m−1) (√ of it for squared_sqrt); +inf when the band makes the end unreachable
  int path_length;  // K of the optimal path, max(n,m) ≤ K ≤ n+m−1; 0 when unreachable
};

// a: n frames × d features, b: m frames × d, both row-major.
// @throws InputError when n < 1, m < 1 or d < 1, or an entry is not finite
DtwResult dtw(const double* a, int n, const double* b, int m, int d, const DtwOptions& opt = {});

}  // namespace divcoll::analysis
