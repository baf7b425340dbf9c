// one agent as data (SPEC §4.1, §4.3, §6.1): its genotypes, the geometry built from them (rest positions
// that training and mutation may move, springs), its controller weights and its connector anchors. The one
// agent type of the code: evolution trains it, the run file stores it (io/run_read.hpp reads it back), the
// ranks send it to each other (mpi/protocol.hpp) and collective/builders.hpp puts it into scenes.
#pragma once

#include <cstdint>
#include <vector>

namespace divcoll::morph {

// the connector anchors of one agent (SPEC §6.1), as local mass indices 0..10 (-1 until computed:
// collective::compute_anchors)
struct Anchors {
  int back_foot = -1, front_foot = -1, back_upper = -1, front_upper = -1;
};

// masses in row-major cell order, springs the lattice edges between them as sorted pairs (morph/body.hpp)
struct Agent {
  uint32_t cells = 0;                       // body genotype (28 lattice cells)
  uint32_t springs = 0;                     // spring genotype (21 bits, 1 = active)
  std::vector<double> rest_pos;             // (11 x 2) u, min x = min y = 0 at the lattice points
  std::vector<int32_t> spring_i, spring_j;  // (21) local mass indices, spring_i < spring_j
  std::vector<double> rest_length;          // (21) u, distance between the rest positions
  std::vector<double> amplitude;            // (21) kActiveAmplitude if active, 0 if passive
  std::vector<double> params;               // (P_a) controller, SPEC §4.3 (empty for a bare body)
  Anchors anchors;                          // filled by collective::compute_anchors

  int n_active() const;  // active springs
};

// body length of an agent: max x − min x of its rest positions, u (SPEC §1)
double body_length(const Agent& a);
// rebuilds rest_length from rest_pos (after the rest positions changed)
void update_rest_lengths(Agent& a);

}  // namespace divcoll::morph
