// behaviour descriptor of an agent body and the uniqueness score of a pool (SPEC §4.2, §4.4).
//
// The descriptor is computed from the rest positions and spring amplitudes of an Agent, so it
// follows the body as gradient descent and mutation move its rest positions. SPEC §4.2 lists nine
// numbers, in this order:
//   0 height   (max y − min y) / (3·0.05·√3/2), the lattice's full height
//   1 width    (max x − min x) / (6·0.05 + 0.025) = / 0.325, the lattice's full width
//   2 aspect   width / height in u / u (not normalised)
//   3 compact  active springs / bounding-box area, 1/u²
//   4 cx       (mean x − min x) / width, in [0, 1]
//   5 cy       (mean y − min y) / height, in [0, 1]
//   6 sd_y     population standard deviation of the masses' y, u ("balance")
//   7 sym_v    reflection symmetry about the vertical centre line x = (min x + max x)/2: the fraction
//              of masses whose mirror image lies within 0.01 u of some mass (itself included)
//   8 sym_h    the same about the horizontal centre line y = (min y + max y)/2
// A zero extent (never seen for a valid body) is replaced by 1e-12 u in every division.
#pragma once

#include <array>
#include <vector>

#include "morph/body.hpp"

namespace divcoll::morph {

inline constexpr int kDescriptorSize = 9;
using Descriptor = std::array<double, kDescriptorSize>;

inline constexpr double kLatticeWidth = 6 * kSpacing + 0.5 * kSpacing;           // u, 0.325
inline constexpr double kLatticeHeight = 3 * kSpacing * 0.86602540378443864676;  // u, 3·0.05·√3/2
inline constexpr double kMirrorTolerance = 0.01;  // u, distance within which a mirror partner counts

Descriptor descriptor(const Agent& g);

// uniqueness of every member of a pool (SPEC §4.4): each dimension is z-scored over the pool (mean and
// population standard deviation); a dimension whose standard deviation is at most 1e-12·max(1, |mean|)
// contributes 0 for everyone. Then, per member, the mean Euclidean distance to its k nearest other
// members (all others when the pool has at most k + 1 members; 0 for a pool of one). Ties in distance
// do not matter: only the distances enter the mean.
std::vector<double> uniqueness(const std::vector<Descriptor>& pool, int k = 5);

}  // namespace divcoll::morph
