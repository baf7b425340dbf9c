// scenes of agents, pairs and chains: placement (SPEC §6.2, §7.4) and anchors (§6.1)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "collective/builders.hpp"
#include "common/check.hpp"
#include "config/environments.hpp"
#include "morph/body.hpp"
#include "sim/engine.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

double min_x_of(const sim::Scene& s, int agent) {
  double m = 1e9;
  for (int q = 0; q < sim::kAgentMasses; ++q) m = std::min(m, s.x0[2 * s.agent_mass_index[agent * 11 + q]]);
  return m;
}
double max_x_of(const sim::Scene& s, int agent) {
  double m = -1e9;
  for (int q = 0; q < sim::kAgentMasses; ++q) m = std::max(m, s.x0[2 * s.agent_mass_index[agent * 11 + q]]);
  return m;
}

morph::Agent agent(uint64_t seed) {
  Rng rng = make_rng(seed, 5, 0);
  morph::Agent a = collective::random_agent(rng);
  a.anchors = collective::compute_anchors(a, testing::kSpec, {}, 300);
  return a;
}

// a bar of 11 cells ... is not a valid body; use the flattest valid body: the one with the most cells in row 0
morph::Agent passive_flat_agent() {
  uint32_t best = 0;
  int best_row0 = -1;
  for (uint32_t cells : morph::all_valid_placements()) {
    const int row0 = __builtin_popcount(cells & 0x7f);
    if (row0 > best_row0) best_row0 = row0, best = cells;
  }
  morph::Agent a;
  a.cells = best;
  a.springs = 1;
  const morph::Agent g = morph::agent_geometry(a.cells, a.springs);
  a.rest_pos = g.rest_pos;
  a.spring_i = g.spring_i;
  a.spring_j = g.spring_j;
  a.rest_length = g.rest_length;
  a.amplitude = std::vector<double>(21, 0.0);           // passive
  a.params = std::vector<double>(3509, 0.0);            // and a silent controller
  return a;
}

TEST(Anchors, PassiveFlatBodyHasFeetOnTheGroundRowAndUppersAbove) {
  const morph::Agent a = passive_flat_agent();
  const morph::Anchors an = collective::compute_anchors(a, testing::kSpec);
  double com = 0;
  for (int q = 0; q < 11; ++q) com += a.rest_pos[2 * q] / 11;
  // resting on its bottom row: every bottom-row mass touches at every step; the tie goes to the lowest
  // rest y, then the lowest index: the back foot is mass 0, the front foot the first bottom-row mass in front
  EXPECT_EQ(an.back_foot, 0);
  int first_front_bottom = -1;
  for (int q = 0; q < 11 && first_front_bottom < 0; ++q)
    if (a.rest_pos[2 * q + 1] == 0 && a.rest_pos[2 * q] >= com) first_front_bottom = q;
  EXPECT_EQ(an.front_foot, first_front_bottom);
  // uppers are on their side, above the median height, and are not the feet
  std::vector<double> ys;
  for (int q = 0; q < 11; ++q) ys.push_back(a.rest_pos[2 * q + 1]);
  std::sort(ys.begin(), ys.end());
  EXPECT_LT(a.rest_pos[2 * an.back_upper], com);
  EXPECT_GE(a.rest_pos[2 * an.front_upper], com);
  EXPECT_GE(a.rest_pos[2 * an.back_upper + 1], ys[5]);
  EXPECT_GE(a.rest_pos[2 * an.front_upper + 1], ys[5]);
  EXPECT_NE(an.back_upper, an.back_foot);
  EXPECT_NE(an.front_upper, an.front_foot);
}

TEST(Pair, AnteriorIsPlacedBehindAGapOfFiveHundredthsAndConnectorIsWellFormed) {
  const morph::Agent p = agent(1), a = agent(2);
  Rng rng = make_rng(1, 6, 0);
  const sim::Scene s = collective::pair_scene(p, a, morph::init_connector_params(rng, morph::kConnectorInitGains[2]), testing::weak_connector(), "flat", testing::kCoulomb);
  EXPECT_EQ(s.n_agents(), 2);
  EXPECT_EQ(s.n_connectors(), 1);
  EXPECT_NEAR(min_x_of(s, 1), max_x_of(s, 0) + 0.05, 1e-15);
  for (int r = 0; r < 5; ++r) {
    const int sp = s.connector_spring_index[r];
    EXPECT_LT(s.spring_i[sp], 11) << "spring i is on the posterior";
    EXPECT_GE(s.spring_j[sp], 11) << "spring j is on the anterior";
    EXPECT_TRUE(std::isfinite(s.rest_length[sp]));
    EXPECT_GT(s.rest_length[sp], 0.05);
    EXPECT_EQ(s.stiffness[sp], testing::weak_connector().stiffness);
    EXPECT_EQ(s.amplitude[sp], 0.6);
  }
  // spring order of SPEC §6.2
  const int sp0 = s.connector_spring_index[0], sp4 = s.connector_spring_index[4];
  EXPECT_EQ(s.spring_i[sp0], p.anchors.front_foot);
  EXPECT_EQ(s.spring_j[sp0], 11 + a.anchors.back_foot);
  EXPECT_EQ(s.spring_i[sp4], p.anchors.back_upper);
  EXPECT_EQ(s.spring_j[sp4], 11 + a.anchors.back_upper);
  // lowest masses on the ground, terrain features start 0.05 ahead of the front
  double ymin = 1e9;
  for (int i = 0; i < s.n_masses(); ++i) ymin = std::min(ymin, s.x0[2 * i + 1]);
  EXPECT_EQ(ymin, 0.0);
  const sim::Scene g = collective::pair_scene(p, a, s.connector_params, testing::weak_connector(), "gap", testing::kCoulomb);
  EXPECT_NEAR(g.env.terrain[1].x_start, max_x_of(g, 1) + 0.05, 1e-15);
  // a tether of another stiffness and amplitude reaches the 5 connector springs and no agent spring
  const sim::Scene t = collective::pair_scene(p, a, s.connector_params, collective::Tether{1234.5, 0.25, 7.5}, "flat", testing::kCoulomb);
  for (int r = 0; r < 5; ++r) {
    EXPECT_EQ(t.stiffness[t.connector_spring_index[r]], 1234.5);
    EXPECT_EQ(t.amplitude[t.connector_spring_index[r]], 0.25);
    EXPECT_EQ(t.damping[t.connector_spring_index[r]], 7.5);
    EXPECT_EQ(s.damping[s.connector_spring_index[r]], 0.0);  // SPEC §6.2: no dashpot by default
  }
  for (int sp : t.agent_spring_index) EXPECT_EQ(t.amplitude[sp], s.amplitude[sp]);
  for (int sp : t.agent_spring_index) EXPECT_EQ(t.damping[sp], 0.0);
}

TEST(Chain, HeapOrderPutsAgentZeroInFrontAndChildrenBehindTheirParent) {
  std::vector<morph::Agent> agents;
  for (int q = 0; q < 7; ++q) agents.push_back(agent(10 + q));
  std::vector<const morph::Agent*> ptr;
  for (const auto& a : agents) ptr.push_back(&a);
  Rng rng = make_rng(2, 6, 0);
  const sim::Scene s = collective::chain_scene(ptr, morph::init_connector_params(rng, morph::kConnectorInitGains[2]), testing::weak_connector(), "flat", testing::kCoulomb);
  EXPECT_EQ(s.n_agents(), 7);
  EXPECT_EQ(s.n_connectors(), 6);
  for (int k = 1; k < 7; ++k) {
    const int parent = (k - 1) / 2;
    EXPECT_NEAR(min_x_of(s, parent), max_x_of(s, k) + 0.05, 1e-12) << "agent " << k;
    const int sp = s.connector_spring_index[(k - 1) * 5];
    EXPECT_EQ(s.spring_i[sp] / 11, k) << "connector " << k - 1 << " starts on the child";
    EXPECT_EQ(s.spring_j[sp] / 11, parent) << "connector " << k - 1 << " ends on the parent";
  }
  for (int k = 1; k < 7; ++k) EXPECT_LT(max_x_of(s, k), min_x_of(s, 0)) << "agent 0 is front-most";
  EXPECT_THROW(collective::chain_scene({ptr[0]}, s.connector_params, testing::weak_connector(), "flat", testing::kCoulomb), InputError);
  // a chain's every connector spring gets the tether's dashpot, no agent spring does
  const sim::Scene d = collective::chain_scene(ptr, s.connector_params, collective::Tether{5e3, 0.6, 3.0}, "flat", testing::kCoulomb);
  for (int sp : d.connector_spring_index) EXPECT_EQ(d.damping[sp], 3.0);
  for (int sp : d.agent_spring_index) EXPECT_EQ(d.damping[sp], 0.0);
}

}  // namespace
}  // namespace divcoll
