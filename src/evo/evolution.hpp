// the evolutionary algorithm of SPEC §4.4: offspring by mutation, deletion by fitness × uniqueness.
// Every random draw of offspring i in generation g comes from make_rng(run seed, stage, i), so the
// result does not depend on who computes it or in which order.
#pragma once

#include <cstdint>
#include <vector>

#include "evo/gd.hpp"
#include "morph/agent.hpp"
#include "morph/descriptor.hpp"

namespace divcoll::evo {

// the [agents] keys mutation reads, taken from the section by mutation_options (defaults: the config's schema,
// mutation_options(config::default_config().agents))
struct MutationOptions {
  double body_flip_p{};
  double spring_flip_p{};
  double rest_jitter_sd{};  // u
  bool body_fixed{};        // graded diversity: the body genotype never mutates
  bool springs_fixed{};     // graded diversity: the spring genotype never mutates
  bool rest_moves{};        // rest positions are jittered (and trained)
};
inline MutationOptions mutation_options(const config::RunConfig::Agents& a) {
  return {a.body_flip_p, a.spring_flip_p, a.rest_jitter_sd, a.body_fixed, a.springs_fixed, a.rest_moves};
}

// one member of a generation's pool
struct Individual {
  morph::Agent agent;
  int64_t id = -1;
  int64_t parent = -1;
  TrainResult train;
  morph::Descriptor descriptor{};
};

// the behaviour descriptor of an agent's body (SPEC §4.2)
morph::Descriptor agent_descriptor(const morph::Agent& a);

// the descriptor for a population of one body shape (graded diversity, SPEC §7.5): entries 7 and 8, the
// body's mirror symmetries (constant over such a population), become the mirror symmetries of its active
// springs: the fraction of active springs whose mirror image (both ends, about the vertical / horizontal
// centre line of the rest positions) lies within 0.01 u of an active spring. Entry 3 (active springs per
// bounding-box area) already depends on the springs; the others are constant and drop out of uniqueness.
morph::Descriptor spring_layout_descriptor(const morph::Agent& a);

// a copy of `parent` (weights and rest positions included) with its body bits flipped and repaired, its
// spring bits flipped, and its rest positions jittered; a changed body starts from its lattice positions
morph::Agent make_offspring(const morph::Agent& parent, Rng& rng, const MutationOptions& opt, const GdOptions& gd);

// SPEC §4.4 deletion: among the pool, repeatedly delete the member with the lowest
// (fitness − min fitness + 1e-6) × uniqueness (uniqueness recomputed over the remaining pool after each
// deletion; members whose training failed are deleted first) until `keep` remain. Returns the indices
// kept, in pool order; `uniqueness_out` (if given) receives each member's uniqueness in the full pool.
// With rank = true the score is (fitness rank + 1) × (uniqueness rank + 1) among the remaining pool (rank
// 0 = lowest): with the paper's score the current minimum always scores ≈ 1e-6 × uniqueness and is
// deleted whatever its uniqueness, so deletion is truncation by fitness (measured: body diversity
// collapses from 61 to 3 placements over 15 generations at paper scale).
std::vector<int> select_survivors(const std::vector<Individual>& pool, int keep, int k,
                                  std::vector<double>* uniqueness_out = nullptr, bool rank = false);

}  // namespace divcoll::evo
