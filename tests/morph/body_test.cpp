// tests of src/morph/body: lattice, validity, enumeration, random draws, repair, geometry, controller
// init, and the deterministic random helpers of src/common/rng.hpp
#include "morph/body.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <set>
#include <utility>

#include "common/check.hpp"
#include "nn/mlp.hpp"

namespace divcoll::morph {
namespace {

// a body from (row, column) pairs
uint32_t cells_of(std::initializer_list<std::pair<int, int>> rc) {
  uint32_t m = 0;
  for (auto [r, c] : rc) m |= 1u << (r * kCols + c);
  return m;
}

// ---- independent checks of §4.1, from the geometry only (cells adjacent = 0.05 u apart) ----------
bool adjacent(int a, int b) {
  const auto p = cell_position(a), q = cell_position(b);
  return a != b && std::abs(std::hypot(p[0] - q[0], p[1] - q[1]) - kSpacing) < 1e-9;
}

int edges_by_distance(uint32_t cells) {
  int e = 0;
  for (int a = 0; a < kCells; ++a)
    for (int b = a + 1; b < kCells; ++b)
      if ((cells >> a & 1) && (cells >> b & 1) && adjacent(a, b)) ++e;
  return e;
}

// cells of `within` reachable from `start` (a set of cells) by adjacency
std::set<int> reach(std::set<int> start, uint32_t within) {
  std::vector<int> stack(start.begin(), start.end());
  while (!stack.empty()) {
    const int a = stack.back();
    stack.pop_back();
    for (int b = 0; b < kCells; ++b)
      if ((within >> b & 1) && adjacent(a, b) && start.insert(b).second) stack.push_back(b);
  }
  return start;
}

bool connected_by_distance(uint32_t cells) {
  if (!cells) return false;
  return static_cast<int>(reach({std::countr_zero(cells)}, cells).size()) == std::popcount(cells);
}

bool hole_free_by_distance(uint32_t cells) {
  // empty cells with fewer than 6 lattice neighbours touch the outside of the box
  const uint32_t empty = kCellMask & ~cells;
  std::set<int> border;
  for (int a = 0; a < kCells; ++a) {
    int deg = 0;
    for (int b = 0; b < kCells; ++b) deg += adjacent(a, b);
    if ((empty >> a & 1) && deg < 6) border.insert(a);
  }
  return static_cast<int>(reach(border, empty).size()) == std::popcount(empty);
}

void expect_valid_by_definition(uint32_t cells) {
  EXPECT_EQ(cells & ~kCellMask, 0u);
  EXPECT_EQ(std::popcount(cells), 11);
  EXPECT_TRUE(connected_by_distance(cells));
  EXPECT_TRUE(hole_free_by_distance(cells));
  EXPECT_EQ(edges_by_distance(cells), 21);
}

// ---- lattice -------------------------------------------------------------------------------------
TEST(BodyLattice, NeighboursAreTheCellsOneSpacingAway) {
  for (int a = 0; a < kCells; ++a)
    for (int b = 0; b < kCells; ++b)
      EXPECT_EQ((cell_neighbours(a) >> b & 1) != 0, adjacent(a, b)) << a << " " << b;
  // the rule of §4.1 spelled out for one even and one odd cell
  EXPECT_EQ(cell_neighbours(2 * 7 + 3), cells_of({{2, 2}, {2, 4}, {1, 2}, {1, 3}, {3, 2}, {3, 3}}));
  EXPECT_EQ(cell_neighbours(1 * 7 + 3), cells_of({{1, 2}, {1, 4}, {0, 3}, {0, 4}, {2, 3}, {2, 4}}));
  const auto p = cell_position(3 * 7 + 6);
  EXPECT_DOUBLE_EQ(p[0], 0.325);
  EXPECT_DOUBLE_EQ(p[1], 0.15 * std::sqrt(3.0) / 2);
}

TEST(BodyLattice, EdgeCountAgreesWithDistances) {
  Rng rng(7);
  for (int t = 0; t < 500; ++t) {
    const uint32_t m = static_cast<uint32_t>(rng()) & kCellMask;
    EXPECT_EQ(lattice_edges(m), edges_by_distance(m));
  }
}

// ---- validity ------------------------------------------------------------------------------------
TEST(BodyValidity, RandomBodiesAreValid) {
  Rng rng(1);
  std::set<uint32_t> shapes;
  for (int t = 0; t < 1000; ++t) {
    const uint32_t b = random_body(rng);
    std::string why;
    EXPECT_TRUE(is_valid_body(b, &why)) << why;
    expect_valid_by_definition(b);
    shapes.insert(shape_of(b));
  }
  // uniform over 20 shapes: 1000 draws reach them all
  EXPECT_EQ(shapes.size(), 20u);
}

TEST(BodyValidity, RefusesAHole) {
  // the six neighbours of (1, 3) around it, plus a tail of five
  const uint32_t b =
      cells_of({{1, 2}, {1, 4}, {0, 3}, {0, 4}, {2, 3}, {2, 4}, {0, 0}, {0, 1}, {0, 2}, {2, 1}, {2, 2}});
  std::string why;
  EXPECT_FALSE(is_valid_body(b, &why));
  EXPECT_NE(why.find("hole at cell (1, 3)"), std::string::npos) << why;
  EXPECT_FALSE(hole_free_by_distance(b));
}

TEST(BodyValidity, RefusesADisconnectedBody) {
  // rows 0 and 2 share no lattice edge
  const uint32_t b =
      cells_of({{0, 0}, {0, 1}, {0, 2}, {0, 3}, {0, 4}, {0, 5}, {2, 0}, {2, 1}, {2, 2}, {2, 3}, {2, 4}});
  std::string why;
  EXPECT_FALSE(is_valid_body(b, &why));
  EXPECT_NE(why.find("not connected"), std::string::npos) << why;
}

TEST(BodyValidity, RefusesTwentyEdges) {
  // connected, no hole, 11 cells, but one edge short
  const uint32_t b =
      cells_of({{0, 0}, {0, 1}, {0, 2}, {0, 3}, {0, 4}, {1, 0}, {1, 1}, {1, 2}, {1, 3}, {2, 1}, {2, 2}});
  ASSERT_TRUE(connected_by_distance(b));
  ASSERT_TRUE(hole_free_by_distance(b));
  ASSERT_EQ(edges_by_distance(b), 20);
  std::string why;
  EXPECT_FALSE(is_valid_body(b, &why));
  EXPECT_NE(why.find("20 lattice edges, needs 21"), std::string::npos) << why;
}

TEST(BodyValidity, RefusesWrongCountAndStrayBits) {
  std::string why;
  EXPECT_FALSE(is_valid_body(0x7ffu >> 1, &why));
  EXPECT_NE(why.find("10 cells, needs 11"), std::string::npos) << why;
  const uint32_t good = all_valid_placements().front();
  EXPECT_FALSE(is_valid_body(good | (1u << 28), &why));
  EXPECT_NE(why.find("bits above"), std::string::npos) << why;
  EXPECT_FALSE(is_valid_springs(0, &why));
  EXPECT_NE(why.find("no active spring"), std::string::npos) << why;
  EXPECT_FALSE(is_valid_springs(1u << 21, &why));
  EXPECT_TRUE(is_valid(Body{good, 1}));
}

// ---- enumeration ---------------------------------------------------------------------------------
TEST(BodyEnumeration, CountsPlacementsAndShapes) {
  // 94 placements, confirmed by an independent Python enumeration of connected 11-cell sets
  const auto& all = all_valid_placements();
  EXPECT_EQ(all.size(), 94u);
  EXPECT_EQ(all, enumerate_valid_placements()) << "the table of placements is not what the enumeration finds";
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end()));
  for (uint32_t b : all) expect_valid_by_definition(b);

  // 20 shapes up to geometric translation (a one-row shift with its half-column offset included)
  const auto shapes = all_valid_bodies_up_to_translation();
  EXPECT_EQ(shapes.size(), 20u);
  EXPECT_TRUE(std::is_sorted(shapes.begin(), shapes.end()));
  for (uint32_t s : shapes) EXPECT_EQ(shape_of(s), s);

  // translating only by columns and by two rows (keeping the row parity) gives SPEC's "about 24"
  std::set<std::vector<std::pair<int, int>>> parity_kept;
  for (uint32_t b : all) {
    int min_x = 99, min_r = 99;
    for (int i = 0; i < kCells; ++i)
      if (b >> i & 1) {
        min_x = std::min(min_x, 2 * (i % 7) + (i / 7) % 2);
        min_r = std::min(min_r, i / 7);
      }
    std::vector<std::pair<int, int>> key{{min_r % 2, -1}};
    for (int i = 0; i < kCells; ++i)
      if (b >> i & 1) key.push_back({2 * (i % 7) + (i / 7) % 2 - min_x, i / 7 - min_r});
    parity_kept.insert(key);
  }
  EXPECT_EQ(parity_kept.size(), 24u);
}

TEST(BodyEnumeration, PlacementsOfAShapeShareTheirGeometry) {
  std::set<std::vector<double>> distinct;
  for (uint32_t b : all_valid_placements()) {
    const auto g = agent_geometry(b, kSpringMask), ref = agent_geometry(shape_of(b), kSpringMask);
    ASSERT_EQ(g.rest_pos.size(), ref.rest_pos.size());
    for (size_t k = 0; k < g.rest_pos.size(); ++k) EXPECT_NEAR(g.rest_pos[k], ref.rest_pos[k], 1e-12);
    EXPECT_EQ(g.spring_i, ref.spring_i);
    EXPECT_EQ(g.spring_j, ref.spring_j);
    // rounded positions tell the shapes apart
    std::vector<double> key;
    for (double v : ref.rest_pos) key.push_back(std::round(v * 1e6));
    distinct.insert(key);
  }
  EXPECT_EQ(distinct.size(), 20u);
}

// ---- repair and mutation -------------------------------------------------------------------------
TEST(BodyRepair, LeavesValidBodiesUnchangedAndDrawsNothing) {
  Rng rng(3), untouched(3);
  for (uint32_t b : all_valid_placements()) EXPECT_EQ(repair_body(b, rng), b);
  EXPECT_EQ(rng(), untouched());
}

TEST(BodyRepair, AlwaysYieldsAValidBodyAtMinimalDistance) {
  Rng rng(4);
  for (int t = 0; t < 2000; ++t) {
    // mutated bodies at the default rate, at a high rate, and arbitrary patterns
    const uint32_t base = random_body(rng);
    const uint32_t patterns[] = {mutate_body(base, rng), mutate_body(base, rng, 0.3),
                                 repair_body(static_cast<uint32_t>(rng()), rng)};
    for (uint32_t b : patterns) {
      std::string why;
      EXPECT_TRUE(is_valid_body(b, &why)) << why;
    }
    // the repair is no farther than any valid body, the one mutated from included
    uint32_t flipped = base ^ (1u << uniform_int(rng, kCells)) ^ (1u << uniform_int(rng, kCells));
    const uint32_t fixed = repair_body(flipped, rng);
    EXPECT_LE(std::popcount(fixed ^ flipped), std::popcount(base ^ flipped));
  }
}

TEST(BodyRepair, SameSeedSameResult) {
  Rng a(11), b(11);
  for (int t = 0; t < 200; ++t) {
    const uint32_t x = static_cast<uint32_t>(a());
    EXPECT_EQ(x, static_cast<uint32_t>(b()));
    EXPECT_EQ(repair_body(x, a), repair_body(x, b));
    EXPECT_EQ(mutate_body(all_valid_placements()[t % 94], a), mutate_body(all_valid_placements()[t % 94], b));
  }
}

TEST(BodySprings, RandomAndMutatedKeepOneActive) {
  Rng rng(5);
  for (int t = 0; t < 1000; ++t) {
    const uint32_t s = random_springs(rng);
    EXPECT_TRUE(is_valid_springs(s));
    EXPECT_TRUE(is_valid_springs(mutate_springs(s, rng)));
  }
  // flipping every bit of an all-active genotype leaves none: one bit comes back
  const uint32_t s = mutate_springs(kSpringMask, rng, 1.0);
  EXPECT_EQ(std::popcount(s), 1);
  EXPECT_EQ(s & ~kSpringMask, 0u);
  // p = 0 changes nothing
  EXPECT_EQ(mutate_springs(0x12345, rng, 0.0), 0x12345u);
}

// ---- geometry ------------------------------------------------------------------------------------
TEST(BodyGeometry, FreshBodyIsTheLattice) {
  Rng rng(6);
  for (int t = 0; t < 200; ++t) {
    const Body body = random_genotype(rng);
    const Agent g = agent_geometry(body);
    const std::vector<int32_t> cell = mass_cells(body.cells);
    ASSERT_EQ(cell.size(), 11u);
    EXPECT_EQ(g.cells, body.cells);
    EXPECT_EQ(g.springs, body.springs);
    EXPECT_TRUE(g.params.empty());
    ASSERT_EQ(g.rest_pos.size(), 22u);
    ASSERT_EQ(g.spring_i.size(), 21u);
    ASSERT_EQ(g.spring_j.size(), 21u);
    ASSERT_EQ(g.rest_length.size(), 21u);
    ASSERT_EQ(g.amplitude.size(), 21u);
    EXPECT_TRUE(std::is_sorted(cell.begin(), cell.end()));

    // min x = min y = 0
    double min_x = 1, min_y = 1;
    for (int k = 0; k < 11; ++k) {
      min_x = std::min(min_x, g.rest_pos[2 * k]);
      min_y = std::min(min_y, g.rest_pos[2 * k + 1]);
    }
    EXPECT_EQ(min_x, 0.0);
    EXPECT_EQ(min_y, 0.0);

    // sorted pairs of lattice neighbours, in lexicographic order, rest length 0.05
    for (int s = 0; s < 21; ++s) {
      EXPECT_LT(g.spring_i[s], g.spring_j[s]);
      if (s > 0) {
        EXPECT_LT(std::make_pair(g.spring_i[s - 1], g.spring_j[s - 1]),
                  std::make_pair(g.spring_i[s], g.spring_j[s]));
      }
      EXPECT_TRUE(adjacent(cell[g.spring_i[s]], cell[g.spring_j[s]]));
      EXPECT_NEAR(g.rest_length[s], 0.05, 1e-12);
      EXPECT_EQ(g.amplitude[s], (body.springs >> s & 1) ? kActiveAmplitude : 0.0);
    }
    EXPECT_EQ(g.n_active(), std::popcount(body.springs));
  }
}

TEST(BodyGeometry, RefusesInvalidGenotypes) {
  const uint32_t good = all_valid_placements().front();
  EXPECT_THROW(agent_geometry(good, 0), InputError);
  EXPECT_THROW(agent_geometry(good ^ 1u, 1), InputError);
}

TEST(BodyGeometry, RestLengthsFollowMovedPositions) {
  Agent g = agent_geometry(all_valid_placements().front(), 1);
  g.rest_pos[0] += 0.003;
  update_rest_lengths(g);
  for (int s = 0; s < 21; ++s) {
    const int i = g.spring_i[s], j = g.spring_j[s];
    EXPECT_DOUBLE_EQ(g.rest_length[s], std::hypot(g.rest_pos[2 * j] - g.rest_pos[2 * i],
                                                  g.rest_pos[2 * j + 1] - g.rest_pos[2 * i + 1]));
  }
}

// ---- controller initialisation -------------------------------------------------------------------
void expect_init_statistics(const nn::Layout& L, const std::array<double, 3>& gains,
                            const std::vector<std::vector<double>>& draws) {
  for (int l = 0; l < L.n_layers(); ++l) {
    const int in = L.sizes[l], out = L.sizes[l + 1];
    // biases exactly zero; weights pooled over the draws
    double sum = 0, sum2 = 0;
    int n = 0;
    for (const auto& p : draws) {
      for (int k = 0; k < out; ++k) EXPECT_EQ(p[L.bias_offset(l) + k], 0.0);
      for (int k = 0; k < in * out; ++k) {
        const double w = p[L.weight_offset(l) + k];
        sum += w;
        sum2 += w * w;
        ++n;
      }
    }
    const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
    const double want = gains[l] * std::sqrt(2.0 / (in + out));
    EXPECT_NEAR(sd, want, 0.1 * want) << "layer " << l;
  }
}

TEST(BodyInit, AgentParamsSizeAndStatistics) {
  Rng rng(8);
  const auto p = init_agent_params(rng);
  EXPECT_EQ(p.size(), 3509u);
  expect_init_statistics(nn::agent_layout(54), kAgentInitGains, {p});
  Rng a(9), b(9), c(10);
  EXPECT_EQ(init_agent_params(a), init_agent_params(b));
  EXPECT_NE(init_agent_params(a), init_agent_params(c));
  EXPECT_EQ(init_agent_params(a, 20).size(), static_cast<size_t>(nn::agent_layout(20).param_count()));
}

TEST(BodyInit, ConnectorParamsSizeAndStatistics) {
  Rng rng(12);
  // the last layer has only 32 weights: pool 40 draws for the statistics
  std::vector<std::vector<double>> draws;
  for (int t = 0; t < 40; ++t) draws.push_back(init_connector_params(rng, kConnectorInitGains[2]));
  EXPECT_EQ(draws[0].size(), 1473u);
  expect_init_statistics(nn::connector_layout(), kConnectorInitGains, draws);
  Rng a(13), b(13);
  EXPECT_EQ(init_connector_params(a, kConnectorInitGains[2]), init_connector_params(b, kConnectorInitGains[2]));
}

// ---- common/rng.hpp ------------------------------------------------------------------------------
TEST(BodyRng, DrawsAreInRangeAndWellSpread) {
  Rng rng(seed_for(1, 2, 3));
  double sum = 0, sum2 = 0, usum = 0;
  std::array<int, 7> hist{};
  const int n = 200000;
  for (int t = 0; t < n; ++t) {
    const double u = uniform01(rng);
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    usum += u;
    const double z = normal(rng);
    sum += z;
    sum2 += z * z;
    ++hist[uniform_int(rng, 7)];
  }
  EXPECT_NEAR(usum / n, 0.5, 0.005);
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sum2 / n, 1.0, 0.02);
  for (int h : hist) EXPECT_NEAR(h, n / 7.0, 0.03 * n / 7.0);
}

TEST(BodyRng, SeedsDependOnEveryArgumentAndOrder) {
  EXPECT_EQ(seed_for(1, 2, 3), seed_for(1, 2, 3));
  std::set<uint64_t> seeds;
  for (uint64_t a = 0; a < 4; ++a)
    for (uint64_t b = 0; b < 4; ++b)
      for (uint64_t c = 0; c < 4; ++c) seeds.insert(seed_for(a, b, c));
  EXPECT_EQ(seeds.size(), 64u);
  // pinned values: the same seeds on every platform
  EXPECT_EQ(splitmix64(0), 0xe220a8397b1dcdafull);
  Rng rng = make_rng(1, 2, 3);
  EXPECT_EQ(rng(), Rng(seed_for(1, 2, 3))());
}

}  // namespace
}  // namespace divcoll::morph
