// the evolutionary algorithm (SPEC §4.4): offspring by mutation (validity, geometry, bounds, the fixed
// genotypes of the graded variant, determinism), deletion by fitness × uniqueness (both scores), and
// the behaviour descriptor of an agent
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "collective/builders.hpp"
#include "evo/evolution.hpp"
#include "evo/gd.hpp"
#include "morph/body.hpp"
#include "morph/descriptor.hpp"

namespace divcoll {
namespace {

constexpr int kM = sim::kAgentMasses;

morph::Agent agent(uint64_t seed) {
  Rng rng = make_rng(seed, 8, 0);
  return collective::random_agent(rng);
}

// a parent whose rest positions moved off the lattice (as after training)
morph::Agent moved_parent(uint64_t seed) {
  morph::Agent a = agent(seed);
  Rng rng = make_rng(seed, 8, 1);
  std::vector<double> d(2 * kM);
  for (double& x : d) x = normal(rng, 0.0, 0.003);
  EXPECT_TRUE(evo::move_rest_positions(a, d, evo::gd_options(config::default_config().agents)));
  return a;
}

double min_coord(const morph::Agent& a, int axis) {
  double m = a.rest_pos[axis];
  for (int q = 0; q < kM; ++q) m = std::min(m, a.rest_pos[2 * q + axis]);
  return m;
}

void expect_valid_child(const morph::Agent& c, const morph::Agent& parent, const evo::GdOptions& gd,
                        const std::string& what) {
  std::string why;
  EXPECT_TRUE(morph::is_valid_body(c.cells, &why)) << what << ": " << why;
  EXPECT_TRUE(morph::is_valid_springs(c.springs, &why)) << what << ": " << why;
  const morph::Agent g = morph::agent_geometry(c.cells, c.springs);
  EXPECT_EQ(c.spring_i, g.spring_i) << what;
  EXPECT_EQ(c.spring_j, g.spring_j) << what;
  EXPECT_EQ(c.amplitude, g.amplitude) << what;
  ASSERT_EQ(c.rest_pos.size(), 2u * kM) << what;
  ASSERT_EQ(c.rest_length.size(), static_cast<size_t>(sim::kAgentSprings)) << what;
  for (int s = 0; s < sim::kAgentSprings; ++s) {
    const double L = std::hypot(c.rest_pos[2 * c.spring_i[s]] - c.rest_pos[2 * c.spring_j[s]],
                                c.rest_pos[2 * c.spring_i[s] + 1] - c.rest_pos[2 * c.spring_j[s] + 1]);
    EXPECT_NEAR(c.rest_length[s], L, 1e-15) << what << " spring " << s;
    EXPECT_GE(c.rest_length[s], gd.rest_length_min * 0.05) << what << " spring " << s;
    EXPECT_LE(c.rest_length[s], gd.rest_length_max * 0.05) << what << " spring " << s;
  }
  EXPECT_EQ(min_coord(c, 0), 0.0) << what;
  EXPECT_EQ(min_coord(c, 1), 0.0) << what;
  EXPECT_EQ(c.params, parent.params) << what << ": the weights are copied";
}

// ---- make_offspring --------------------------------------------------------------------------------

TEST(EvolutionOffspring, ChildIsValidAndMatchesItsGenotype) {
  const evo::GdOptions gd = evo::gd_options(config::default_config().agents);
  for (double p : {-1.0, 0.2}) {  // -1: the defaults; 0.2: many flips, so that repair is exercised
    evo::MutationOptions opt = evo::mutation_options(config::default_config().agents);
    if (p > 0) opt.body_flip_p = opt.spring_flip_p = p;
    int body_changed = 0, springs_changed = 0;
    for (int i = 0; i < 200; ++i) {
      const morph::Agent parent = moved_parent(1 + i % 7);
      Rng rng = make_rng(42, 3, i);
      const morph::Agent c = evo::make_offspring(parent, rng, opt, gd);
      expect_valid_child(c, parent, gd, "p " + std::to_string(p) + " child " + std::to_string(i));
      body_changed += c.cells != parent.cells;
      springs_changed += c.springs != parent.springs;
    }
    EXPECT_GT(body_changed, 0) << "p " << p;
    EXPECT_GT(springs_changed, 0) << "p " << p;
    EXPECT_LT(body_changed, 200) << "p " << p;
  }
}

TEST(EvolutionOffspring, NewBodyStartsFromItsLatticeAndOldBodyKeepsItsPositions) {
  const evo::GdOptions gd = evo::gd_options(config::default_config().agents);
  evo::MutationOptions opt = evo::mutation_options(config::default_config().agents);
  opt.body_flip_p = 0.1;
  opt.rest_jitter_sd = 0;
  int seen_new = 0, seen_old = 0;
  for (int i = 0; i < 100; ++i) {
    const morph::Agent parent = moved_parent(3 + i % 5);
    Rng rng = make_rng(7, 3, i);
    const morph::Agent c = evo::make_offspring(parent, rng, opt, gd);
    if (c.cells != parent.cells) {
      ++seen_new;
      EXPECT_EQ(c.rest_pos, morph::agent_geometry(c.cells, c.springs).rest_pos) << "child " << i;
    } else {
      ++seen_old;
      EXPECT_EQ(c.rest_pos, parent.rest_pos) << "child " << i;
    }
  }
  EXPECT_GT(seen_new, 0);
  EXPECT_GT(seen_old, 0);
}

TEST(EvolutionOffspring, SameSeedSameChild) {
  const evo::GdOptions gd = evo::gd_options(config::default_config().agents);
  evo::MutationOptions opt = evo::mutation_options(config::default_config().agents);
  opt.body_flip_p = opt.spring_flip_p = 0.1;
  for (int i = 0; i < 20; ++i) {
    const morph::Agent parent = moved_parent(10 + i);
    Rng r1 = make_rng(5, 4, i), r2 = make_rng(5, 4, i), r3 = make_rng(5, 4, i + 1000);
    const morph::Agent a = evo::make_offspring(parent, r1, opt, gd);
    const morph::Agent b = evo::make_offspring(parent, r2, opt, gd);
    const morph::Agent c = evo::make_offspring(parent, r3, opt, gd);
    EXPECT_EQ(a.cells, b.cells);
    EXPECT_EQ(a.springs, b.springs);
    EXPECT_EQ(a.rest_pos, b.rest_pos);
    EXPECT_EQ(a.rest_length, b.rest_length);
    EXPECT_EQ(a.spring_i, b.spring_i);
    EXPECT_EQ(a.amplitude, b.amplitude);
    EXPECT_EQ(a.params, b.params);
    EXPECT_EQ(r1(), r2()) << "the same number of draws";
    EXPECT_NE(a.rest_pos, c.rest_pos) << "another seed jitters differently";
  }
}

TEST(EvolutionOffspring, FixedGenotypesNeverChange) {
  const evo::GdOptions gd = evo::gd_options(config::default_config().agents);
  for (int which = 0; which < 2; ++which) {
    evo::MutationOptions opt = evo::mutation_options(config::default_config().agents);
    opt.body_flip_p = opt.spring_flip_p = 0.3;  // flips would be frequent
    (which == 0 ? opt.body_fixed : opt.springs_fixed) = true;
    const morph::Agent parent = agent(50 + which);
    int other_changed = 0;
    for (int i = 0; i < 200; ++i) {
      Rng rng = make_rng(9, 3, i);
      const morph::Agent c = evo::make_offspring(parent, rng, opt, gd);
      if (which == 0) {
        ASSERT_EQ(c.cells, parent.cells) << "body_fixed, child " << i;
        other_changed += c.springs != parent.springs;
      } else {
        ASSERT_EQ(c.springs, parent.springs) << "springs_fixed, child " << i;
        other_changed += c.cells != parent.cells;
      }
      expect_valid_child(c, parent, gd, "child " + std::to_string(i));
    }
    EXPECT_GT(other_changed, 100) << "the other genotype still mutates";
  }
}

// everything equal bit for bit except rest lengths, which may differ in the last bit (see below)
void expect_same_agent(const morph::Agent& c, const morph::Agent& p, const std::string& what) {
  EXPECT_EQ(c.cells, p.cells) << what;
  EXPECT_EQ(c.springs, p.springs) << what;
  EXPECT_EQ(c.rest_pos, p.rest_pos) << what;
  EXPECT_EQ(c.spring_i, p.spring_i) << what;
  EXPECT_EQ(c.spring_j, p.spring_j) << what;
  EXPECT_EQ(c.amplitude, p.amplitude) << what;
  EXPECT_EQ(c.params, p.params) << what;
  ASSERT_EQ(c.rest_length.size(), p.rest_length.size()) << what;
  for (size_t s = 0; s < c.rest_length.size(); ++s) EXPECT_NEAR(c.rest_length[s], p.rest_length[s], 1e-16) << what;
}

TEST(EvolutionOffspring, NoFlipsNoJitterGiveTheParentBack) {
  const evo::GdOptions gd = evo::gd_options(config::default_config().agents);
  evo::MutationOptions opt = evo::mutation_options(config::default_config().agents);
  opt.body_flip_p = opt.spring_flip_p = 0;
  opt.rest_jitter_sd = 0;
  evo::MutationOptions no_moves = opt;
  no_moves.rest_jitter_sd = 0.005;
  no_moves.rest_moves = false;  // no jitter when rest positions do not move
  for (int i = 0; i < 20; ++i) {
    for (const morph::Agent& parent : {agent(20 + i), moved_parent(20 + i)}) {
      Rng rng = make_rng(1, 3, i);
      expect_same_agent(evo::make_offspring(parent, rng, opt, gd), parent, "parent " + std::to_string(i));
      expect_same_agent(evo::make_offspring(parent, rng, no_moves, gd), parent, "rest_moves off " + std::to_string(i));
    }
  }
}

TEST(EvolutionOffspring, NoFlipsNoJitterKeepRestLengthsBitForBit) {
  const evo::GdOptions gd = evo::gd_options(config::default_config().agents);
  evo::MutationOptions opt = evo::mutation_options(config::default_config().agents);
  opt.body_flip_p = opt.spring_flip_p = 0;
  opt.rest_jitter_sd = 0;
  for (int i = 0; i < 20; ++i) {
    const morph::Agent fresh = agent(60 + i), moved = moved_parent(60 + i);
    Rng rng = make_rng(1, 3, i);
    EXPECT_EQ(evo::make_offspring(fresh, rng, opt, gd).rest_length, fresh.rest_length) << "fresh parent " << i;
    EXPECT_EQ(evo::make_offspring(moved, rng, opt, gd).rest_length, moved.rest_length) << "moved parent " << i;
    // a moved agent's rest lengths are the distances of its rest positions
    morph::Agent again = moved;
    morph::update_rest_lengths(again);
    EXPECT_EQ(again.rest_length, moved.rest_length) << "moved parent " << i;
  }
}

// ---- select_survivors ------------------------------------------------------------------------------

evo::Individual member(double fitness, morph::Descriptor d, sim::Status status = sim::Status::ok) {
  evo::Individual m;
  m.train.fitness_bl = fitness;
  m.train.travel_u = fitness * 0.3;
  m.train.status = status;
  m.descriptor = d;
  return m;
}

// a descriptor that varies in its first two dimensions only
morph::Descriptor at(double a, double b = 0) {
  morph::Descriptor d{};
  for (int q = 0; q < morph::kDescriptorSize; ++q) d[q] = 0.5 + 0.1 * q;
  d[0] = a, d[1] = b;
  return d;
}

std::vector<int> without(int n, std::vector<int> gone) {
  std::vector<int> keep;
  for (int i = 0; i < n; ++i)
    if (std::find(gone.begin(), gone.end(), i) == gone.end()) keep.push_back(i);
  return keep;
}

TEST(EvolutionSelect, KeepsExactlyKeepInPoolOrderAndReportsUniqueness) {
  Rng rng = make_rng(4, 4, 0);
  std::vector<evo::Individual> pool;
  std::vector<morph::Descriptor> ds;
  for (int i = 0; i < 30; ++i) {
    morph::Descriptor d;
    for (double& x : d) x = uniform01(rng);
    ds.push_back(d);
    pool.push_back(member(normal(rng), d));
  }
  for (bool rank : {false, true}) {
    for (int keep : {29, 15, 1}) {
      std::vector<double> u;
      const std::vector<int> kept = evo::select_survivors(pool, keep, 5, &u, rank);
      ASSERT_EQ(kept.size(), static_cast<size_t>(keep)) << "rank " << rank;
      for (size_t q = 0; q < kept.size(); ++q) {
        EXPECT_GE(kept[q], 0);
        EXPECT_LT(kept[q], 30);
        if (q > 0) {
          EXPECT_LT(kept[q - 1], kept[q]) << "increasing pool order";
        }
      }
      ASSERT_EQ(u.size(), pool.size());
      EXPECT_EQ(u, morph::uniqueness(ds, 5));
    }
    // nothing to delete: everyone stays
    EXPECT_EQ(evo::select_survivors(pool, 30, 5, nullptr, rank), without(30, {}));
    EXPECT_EQ(evo::select_survivors(pool, 40, 5, nullptr, rank), without(30, {}));
  }
}

TEST(EvolutionSelect, FailedMembersAreDeletedFirst) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (bool rank : {false, true}) {
    std::vector<evo::Individual> pool;
    for (int i = 0; i < 8; ++i) pool.push_back(member(1.0 + i, at(i, i % 3)));
    // member 6: the fittest and the most unique, but its training ended in NaN
    pool[6] = member(100.0, at(50, 50), sim::Status::nan);
    EXPECT_EQ(evo::select_survivors(pool, 7, 5, nullptr, rank), without(8, {6})) << "rank " << rank;
    // member 2: status ok but a NaN fitness; unstable member 4 with a finite fitness: both failed
    pool[2] = member(nan, at(2, 2));
    pool[4] = member(9.0, at(40, -40), sim::Status::unstable);
    EXPECT_EQ(evo::select_survivors(pool, 5, 5, nullptr, rank), without(8, {2, 4, 6})) << "rank " << rank;
    // the lowest index among the failed goes first
    EXPECT_EQ(evo::select_survivors(pool, 7, 5, nullptr, rank), without(8, {2})) << "rank " << rank;
  }
}

TEST(EvolutionSelect, PaperScoreWithEqualUniquenessDeletesTheLowestFitness) {
  // two members: each one's uniqueness is the distance to the other, equal bit for bit
  for (double f0 : {1.0, 3.0}) {
    std::vector<evo::Individual> pool = {member(f0, at(0)), member(2.0, at(1, 1))};
    std::vector<double> u;
    const std::vector<int> kept = evo::select_survivors(pool, 1, 5, &u, false);
    ASSERT_EQ(u[0], u[1]);
    EXPECT_EQ(kept, std::vector<int>{f0 > 2.0 ? 0 : 1});
  }
  // the four corners of a square: equal uniqueness; fitness ranks shuffled against the index
  const double fit[4] = {4.0, 2.0, 3.0, 1.0};
  std::vector<evo::Individual> pool;
  for (int i = 0; i < 4; ++i) pool.push_back(member(fit[i], at(i % 2, i / 2)));
  std::vector<double> u;
  EXPECT_EQ(evo::select_survivors(pool, 3, 5, &u, false), without(4, {3}));
  for (int i = 1; i < 4; ++i) EXPECT_NEAR(u[i], u[0], 1e-12);
  EXPECT_EQ(evo::select_survivors(pool, 2, 5, nullptr, false), without(4, {1, 3}));
}

TEST(EvolutionSelect, DuplicatePairLosesOneMemberBeforeAUniqueOne) {
  // eleven members on a line at 0..9 with position 5 taken twice; all equally fit. With k = 5 a copy
  // of the pair scores uniqueness 1.2 (in spacings), every unique member at least 1.4
  for (bool rank : {false, true}) {
    for (int dup_index : {5, 10}) {
      std::vector<evo::Individual> pool;
      for (int i = 0; i < 10; ++i) pool.push_back(member(2.0, at(i)));
      pool.insert(pool.begin() + dup_index, member(2.0, at(5)));
      const int a = 5, b = dup_index == 5 ? 6 : 10;  // the pair's indices
      const std::vector<int> kept = evo::select_survivors(pool, 10, 5, nullptr, rank);
      ASSERT_EQ(kept.size(), 10u);
      const bool lost_a = std::find(kept.begin(), kept.end(), a) == kept.end();
      const bool lost_b = std::find(kept.begin(), kept.end(), b) == kept.end();
      EXPECT_TRUE(lost_a || lost_b) << "rank " << rank << ", pair at " << a << " and " << b;
      // with k = 1 the pair's members have uniqueness 0: one of them goes whatever the fitness (paper score)
      if (!rank) {
        for (auto& m : pool) m.train.fitness_bl = 1.0 + 0.01 * (&m - pool.data());
        const std::vector<int> k1 = evo::select_survivors(pool, 10, 1, nullptr, false);
        EXPECT_TRUE(std::find(k1.begin(), k1.end(), a) == k1.end() || std::find(k1.begin(), k1.end(), b) == k1.end());
      }
    }
  }
}

TEST(EvolutionSelect, RankScoreBreaksTiesByPoolIndex) {
  // two members of equal uniqueness: the fitter one must stay
  std::vector<evo::Individual> two = {member(3.0, at(0)), member(1.0, at(1, 1))};
  EXPECT_EQ(evo::select_survivors(two, 1, 5, nullptr, true), std::vector<int>{0});
  // k = 1, equal fitness: a unique member at 0, another at 10, an identical pair at 1 (indices 2, 3)
  std::vector<evo::Individual> pool = {member(1.0, at(0)), member(1.0, at(10)), member(1.0, at(1)), member(1.0, at(1))};
  const std::vector<int> kept = evo::select_survivors(pool, 3, 1, nullptr, true);
  EXPECT_TRUE(kept == without(4, {2}) || kept == without(4, {3})) << "deleted a unique member";
}

TEST(EvolutionSelect, RankScoreSparesAUniqueLowFitnessMemberThatPaperScoreDeletes) {
  // a far-away member with the lowest fitness: the paper's score deletes the minimum whatever its
  // uniqueness, the rank score deletes a crowded, moderately fit member instead
  // members 0 and 1 share a descriptor, so 1 (second-lowest fitness) is the most crowded
  std::vector<evo::Individual> pool;
  const double fit[8] = {5.0, 2.0, 6.0, 7.0, 3.0, 8.0, 4.0, 0.5};
  const double pos[8] = {0, 0, 0.03, 0.06, 0.1, 0.15, 0.21, 30};
  for (int i = 0; i < 8; ++i) pool.push_back(member(fit[i], at(pos[i], i == 7 ? 30 : 0)));
  EXPECT_EQ(evo::select_survivors(pool, 7, 3, nullptr, false), without(8, {7}));
  const std::vector<int> kept = evo::select_survivors(pool, 7, 3, nullptr, true);
  EXPECT_EQ(kept, without(8, {1}));
  EXPECT_NE(std::find(kept.begin(), kept.end(), 7), kept.end());
}

// ---- agent_descriptor ------------------------------------------------------------------------------

TEST(EvolutionDescriptor, FreshAgentMatchesMorphDescriptorAndMovedAgentFollowsItsPositions) {
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    const morph::Agent a = agent(seed);
    EXPECT_EQ(evo::agent_descriptor(a), morph::descriptor(morph::agent_geometry(a.cells, a.springs))) << seed;
    const morph::Agent m = moved_parent(seed);
    morph::Agent g = morph::agent_geometry(m.cells, m.springs);
    g.rest_pos = m.rest_pos;
    morph::update_rest_lengths(g);
    EXPECT_EQ(evo::agent_descriptor(m), morph::descriptor(g)) << seed;
    EXPECT_NE(evo::agent_descriptor(m), evo::agent_descriptor(a)) << seed;
  }
}

}  // namespace
}  // namespace divcoll
