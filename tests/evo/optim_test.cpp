// the optimizers (evo/optim.hpp): Adam's first step, its clipping, the normalized step; and that Adam
// descending −g is, bit for bit, the ascent the agents' gd_rule = adam took before it used this module
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/rng.hpp"
#include "evo/optim.hpp"

namespace divcoll {
namespace {

TEST(Optimizers, AdamFirstStepIsLrTimesSignAndClipScalesTheGradient) {
  evo::Adam adam;
  std::vector<double> p = {1.0, 2.0, 3.0};
  adam.step(p, {0.5, -2.0, 0.0}, 0.01, 1e6, 1);
  EXPECT_NEAR(p[0], 1.0 - 0.01, 1e-9);
  EXPECT_NEAR(p[1], 2.0 + 0.01, 1e-9);
  EXPECT_DOUBLE_EQ(p[2], 3.0);
  // clipping: the first moment holds the clipped gradient
  evo::Adam c;
  std::vector<double> q = {0.0, 0.0};
  c.step(q, {3.0, 4.0}, 0.01, 1.0, 1);
  EXPECT_NEAR(c.m[0], 0.1 * 0.6, 1e-12);
  EXPECT_NEAR(c.m[1], 0.1 * 0.8, 1e-12);
  std::vector<double> r = {1.0, 1.0};
  evo::normalized_step(r, {3.0, 4.0}, 0.5);
  EXPECT_NEAR(r[0], 1.0 - 0.3, 1e-12);
  EXPECT_NEAR(r[1], 1.0 - 0.4, 1e-12);
}

TEST(Optimizers, AdamOnTheNegatedGradientIsTheAscentBitForBit) {
  // the ascent gd.cpp wrote out before (m, v on +g; θ += lr·m̂/(√v̂ + ε)), step by step
  Rng rng = make_rng(5, 6, 7);
  std::vector<double> up(40), down, m(40, 0.0), v(40, 0.0);
  for (double& x : up) x = normal(rng);
  down = up;
  evo::Adam adam;
  for (int t = 1; t <= 5; ++t) {
    std::vector<double> g(40), neg(40);
    for (size_t q = 0; q < g.size(); ++q) g[q] = normal(rng), neg[q] = -g[q];
    const double b1 = 0.9, b2 = 0.999, eps = 1e-8, c1 = 1 - std::pow(b1, t), c2 = 1 - std::pow(b2, t);
    for (size_t q = 0; q < g.size(); ++q) {
      m[q] = b1 * m[q] + (1 - b1) * g[q];
      v[q] = b2 * v[q] + (1 - b2) * g[q] * g[q];
      up[q] += 0.01 * (m[q] / c1) / (std::sqrt(v[q] / c2) + eps);
    }
    adam.step(down, neg, 0.01, std::numeric_limits<double>::infinity(), t);
    for (size_t q = 0; q < g.size(); ++q) ASSERT_EQ(up[q], down[q]) << "step " << t << ", parameter " << q;
  }
}

}  // namespace
}  // namespace divcoll
