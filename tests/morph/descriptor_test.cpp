// tests of src/morph/descriptor: the behaviour descriptor of a body and the uniqueness of a pool
#include "morph/descriptor.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/check.hpp"

namespace divcoll::morph {
namespace {

// a geometry with the given rest positions (u) and no springs
Agent points(std::vector<double> pos) {
  Agent g;
  g.rest_pos = std::move(pos);
  return g;
}

TEST(Descriptor, FreshBodiesStayInRange) {
  for (uint32_t b : all_valid_bodies_up_to_translation()) {
    const Descriptor d = descriptor(agent_geometry(b, kSpringMask));
    EXPECT_GT(d[0], 0.0);
    EXPECT_LE(d[0], 1.0 + 1e-12);
    EXPECT_GT(d[1], 0.0);
    EXPECT_LE(d[1], 1.0 + 1e-12);
    EXPECT_NEAR(d[2], d[1] * kLatticeWidth / (d[0] * kLatticeHeight), 1e-12);
    for (int k : {4, 5, 7, 8}) {
      EXPECT_GE(d[k], 0.0);
      EXPECT_LE(d[k], 1.0);
    }
    EXPECT_GT(d[6], 0.0);
  }
}

TEST(Descriptor, KnownShape) {
  // rows 0..2 with 4, 4, 3 cells: 0.15 u high, 0.175 u wide, every spring active
  const uint32_t b = 0x003878f;
  const Descriptor d = descriptor(agent_geometry(b, kSpringMask));
  const double h = 2 * 0.05 * std::sqrt(3.0) / 2, w = 0.175;
  EXPECT_NEAR(d[0], 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(d[1], w / 0.325, 1e-12);
  EXPECT_NEAR(d[2], w / h, 1e-12);
  EXPECT_NEAR(d[3], 21 / (w * h), 1e-9);
  // active springs only: one active spring divides by the same area
  EXPECT_NEAR(descriptor(agent_geometry(b, 1))[3], 1 / (w * h), 1e-9);
  // rows hold 4, 4, 3 masses at heights 0, h/2, h
  EXPECT_NEAR(d[5], (4 * 0.5 + 3 * 1.0) / 11, 1e-12);
}

TEST(Descriptor, SymmetricBodyHasVerticalSymmetryOne) {
  // a lattice trapezoid symmetric about x = 0.075: 4 at the bottom, 3 above, 2 above that
  const double r = 0.05 * std::sqrt(3.0) / 2;
  const Agent g =
      points({0, 0, 0.05, 0, 0.1, 0, 0.15, 0, 0.025, r, 0.075, r, 0.125, r, 0.05, 2 * r, 0.1, 2 * r});
  const Descriptor d = descriptor(g);
  EXPECT_EQ(d[7], 1.0);
  EXPECT_NEAR(d[4], 0.5, 1e-12);
  // not symmetric up-down: the outer two masses of the bottom row have no partner
  EXPECT_NEAR(d[8], 7.0 / 9.0, 1e-12);

  // moving one mass by 0.02 u breaks its pair (and the mirror of its partner)
  Agent moved = g;
  moved.rest_pos[2 * 4 + 1] += 0.02;
  EXPECT_LT(descriptor(moved)[7], 1.0);
  // moving it by less than the tolerance keeps it
  moved.rest_pos[2 * 4 + 1] = r + 0.005;
  EXPECT_EQ(descriptor(moved)[7], 1.0);
}

TEST(Descriptor, MirrorImageSwapsTheCentroid) {
  for (uint32_t b : all_valid_bodies_up_to_translation()) {
    const Agent g = agent_geometry(b, kSpringMask);
    Agent m = g;
    double max_x = 0;
    for (int k = 0; k < 11; ++k) max_x = std::max(max_x, g.rest_pos[2 * k]);
    for (int k = 0; k < 11; ++k) m.rest_pos[2 * k] = max_x - g.rest_pos[2 * k];
    const Descriptor d = descriptor(g), e = descriptor(m);
    for (int k : {0, 1, 2, 3, 5, 6, 7, 8}) EXPECT_NEAR(d[k], e[k], 1e-9) << k;
    EXPECT_NEAR(d[4], 1 - e[4], 1e-12);
  }
}

// a pool of descriptors of all shapes with various spring counts
std::vector<Descriptor> shape_pool() {
  std::vector<Descriptor> pool;
  Rng rng(21);
  for (uint32_t b : all_valid_bodies_up_to_translation())
    for (int t = 0; t < 3; ++t) pool.push_back(descriptor(agent_geometry(b, random_springs(rng))));
  return pool;
}

TEST(DescriptorUniqueness, OutlierIsLargest) {
  auto pool = shape_pool();
  // a long flat body: far from every lattice shape
  Descriptor out = pool[0];
  out[0] = 0.2;
  out[1] = 1.5;
  out[2] = 10;
  pool.push_back(out);
  const auto u = uniqueness(pool);
  ASSERT_EQ(u.size(), pool.size());
  EXPECT_EQ(std::max_element(u.begin(), u.end()) - u.begin(), static_cast<long>(pool.size()) - 1);
}

TEST(DescriptorUniqueness, InvariantToScalingOneDimension) {
  const auto pool = shape_pool();
  const auto u = uniqueness(pool);
  for (int d = 0; d < kDescriptorSize; ++d) {
    auto scaled = pool;
    for (auto& x : scaled) x[d] = 1000 * x[d] + 7;
    const auto v = uniqueness(scaled);
    for (size_t i = 0; i < u.size(); ++i) EXPECT_NEAR(u[i], v[i], 1e-9 * (1 + u[i])) << d;
  }
}

TEST(DescriptorUniqueness, KnownValuesAndEdgeCases) {
  // two members: z-scores ±1 in each varying dimension, so the distance is 2·sqrt(varying dims)
  Descriptor a{}, b{};
  b[0] = 3;
  b[4] = -1;
  a[7] = b[7] = 0.5;  // constant: contributes nothing
  auto u = uniqueness({a, b});
  EXPECT_NEAR(u[0], 2 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(u[1], 2 * std::sqrt(2.0), 1e-12);

  // k larger than the pool uses every other member; a pool of one scores 0
  Descriptor c = b;
  c[0] = 6;
  EXPECT_EQ(uniqueness({a, b, c}, 5), uniqueness({a, b, c}, 2));
  EXPECT_EQ(uniqueness({a}), std::vector<double>{0.0});
  EXPECT_TRUE(uniqueness({}).empty());
  EXPECT_THROW(uniqueness({a, b}, 0), InputError);

  // k = 1 is the nearest-neighbour distance
  u = uniqueness({a, b, c}, 1);
  EXPECT_NEAR(u[1], std::min(u[0], u[2]), 1e-12);
}

}  // namespace
}  // namespace divcoll::morph
