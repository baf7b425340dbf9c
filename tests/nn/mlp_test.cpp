// the controllers' MLP: forward against a plain reference, backward against central differences,
// the vectorised tanh against std::tanh; the kernels' float instantiation against the double one
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "common/rng.hpp"
#include "nn/mlp.hpp"

namespace divcoll {
namespace {

std::vector<double> random_vec(size_t n, uint64_t seed, double sd) {
  Rng rng = make_rng(seed, 0, n);
  std::vector<double> v(n);
  for (double& x : v) x = sd * normal(rng);
  return v;
}

// plain loops: y = tanh(W x + b) per layer
std::vector<double> reference_forward(const nn::Layout& L, const std::vector<double>& p, std::vector<double> x) {
  for (int l = 0; l < L.n_layers(); ++l) {
    std::vector<double> y(L.sizes[l + 1]);
    for (int o = 0; o < L.sizes[l + 1]; ++o) {
      double z = p[L.bias_offset(l) + o];
      for (int i = 0; i < L.sizes[l]; ++i) z += p[L.weight_offset(l) + o * L.sizes[l] + i] * x[i];
      y[o] = std::tanh(z);
    }
    x = y;
  }
  return x;
}

TEST(Mlp, ParameterCountsMatchTheSpec) {
  EXPECT_EQ(nn::agent_layout(54).param_count(), 3509);
  EXPECT_EQ(nn::connector_layout().param_count(), 1473);
  EXPECT_EQ(nn::agent_layout(54).bias_offset(0), 54 * 32);
  EXPECT_EQ(nn::agent_layout(54).weight_offset(1), 54 * 32 + 32);
}

TEST(Mlp, TanhMatchesStdTanh) {
  std::vector<double> x;
  for (double v = -30; v <= 30; v += 0.001) x.push_back(v);
  x.push_back(1e-300);
  x.push_back(-1e-12);
  std::vector<double> y = x;
  nn::tanh_inplace(y.data(), static_cast<int>(y.size()));
  for (size_t i = 0; i < x.size(); ++i) ASSERT_NEAR(y[i], std::tanh(x[i]), 4e-16) << "x = " << x[i];
  std::vector<double> special = {INFINITY, -INFINITY, NAN};
  nn::tanh_inplace(special.data(), 3);
  EXPECT_EQ(special[0], 1.0);
  EXPECT_EQ(special[1], -1.0);
  EXPECT_TRUE(std::isnan(special[2]));
}

TEST(Mlp, FloatTanhMatchesStdTanh) {
  std::vector<float> x;
  for (double v = -30; v <= 30; v += 0.001) x.push_back(static_cast<float>(v));
  x.push_back(1e-30f);
  x.push_back(-1e-12f);
  std::vector<float> y = x;
  nn::tanh_inplace(y.data(), static_cast<int>(y.size()));
  // float's own rounding of the result is up to 6e-8 near ±1; the algorithm adds less than that again
  for (size_t i = 0; i < x.size(); ++i) ASSERT_NEAR(y[i], std::tanh(static_cast<double>(x[i])), 1.2e-7) << "x = " << x[i];
  std::vector<float> special = {INFINITY, -INFINITY, NAN};
  nn::tanh_inplace(special.data(), 3);
  EXPECT_EQ(special[0], 1.0f);
  EXPECT_EQ(special[1], -1.0f);
  EXPECT_TRUE(std::isnan(special[2]));
}

class MlpLayouts : public ::testing::TestWithParam<int> {};

// forward and backward of the packed kernels in T, on parameters packed from double and inputs rounded to T
template <class T>
struct PackedRun {
  std::vector<T> acts, param_grad, in_grad;
  PackedRun(const nn::Layout& L, const std::vector<double>& p, const std::vector<double>& in,
            const std::vector<double>& out_grad, int cols) {
    std::vector<T> packed(nn::packed_count<T>(L));
    nn::pack(L, p.data(), packed.data());
    acts.assign(static_cast<size_t>(L.activation_count()) * cols, T(0));
    for (size_t q = 0; q < in.size(); ++q) acts[q] = static_cast<T>(in[q]);
    nn::forward_packed(L, packed.data(), cols, acts.data());
    std::vector<T> og(out_grad.begin(), out_grad.end()), scratch(static_cast<size_t>(L.scratch_count()) * cols);
    param_grad.assign(L.param_count(), T(0));
    in_grad.assign(static_cast<size_t>(L.in()) * cols, T(0));
    nn::backward_packed(L, packed.data(), cols, acts.data(), og.data(), param_grad.data(), in_grad.data(), scratch.data());
  }
};

// float follows double to float's precision: outputs within 2e-6, gradients within 2e-5 of the largest
TEST_P(MlpLayouts, FloatFollowsDouble) {
  const nn::Layout L = GetParam() == 0 ? nn::agent_layout(54) : nn::connector_layout();
  const int cols = 5;
  const std::vector<double> p = random_vec(L.param_count(), 11, 0.3);
  const std::vector<double> in = random_vec(L.in() * cols, 12, 1.0);
  const std::vector<double> og = random_vec(L.out() * cols, 13, 1.0);
  const PackedRun<double> d(L, p, in, og, cols);
  const PackedRun<float> f(L, p, in, og, cols);
  for (size_t q = 0; q < d.acts.size(); ++q) ASSERT_NEAR(f.acts[q], d.acts[q], 2e-6) << "activation " << q;
  auto largest = [](const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m = std::max(m, std::abs(x));
    return m;
  };
  const double gp = largest(d.param_grad), gx = largest(d.in_grad);
  ASSERT_GT(gp, 0.01);
  ASSERT_GT(gx, 0.01);
  for (size_t q = 0; q < d.param_grad.size(); ++q) ASSERT_NEAR(f.param_grad[q], d.param_grad[q], 2e-5 * gp) << "parameter " << q;
  for (size_t q = 0; q < d.in_grad.size(); ++q) ASSERT_NEAR(f.in_grad[q], d.in_grad[q], 2e-5 * gx) << "input " << q;
}

// a column's float outputs and input gradient are the same bits whether it is computed among 7 columns or alone
TEST_P(MlpLayouts, FloatColumnGivesTheSameBitsAmongOthersAndAlone) {
  const nn::Layout L = GetParam() == 0 ? nn::agent_layout(54) : nn::connector_layout();
  const int cols = 7;
  const std::vector<double> p = random_vec(L.param_count(), 21, 0.3);
  const std::vector<double> in = random_vec(L.in() * cols, 22, 1.0);
  const std::vector<double> og = random_vec(L.out() * cols, 23, 1.0);
  const PackedRun<float> all(L, p, in, og, cols);
  for (int c = 0; c < cols; ++c) {
    const PackedRun<float> one(L, p, std::vector<double>(in.begin() + c * L.in(), in.begin() + (c + 1) * L.in()),
                               std::vector<double>(og.begin() + c * L.out(), og.begin() + (c + 1) * L.out()), 1);
    for (int l = 1; l <= L.n_layers(); ++l)
      ASSERT_EQ(std::memcmp(&all.acts[static_cast<size_t>(L.activation_offset(l)) * cols + static_cast<size_t>(c) * L.sizes[l]],
                            &one.acts[L.activation_offset(l)], sizeof(float) * L.sizes[l]),
                0)
          << "column " << c << ", layer " << l;
    ASSERT_EQ(std::memcmp(&all.in_grad[static_cast<size_t>(c) * L.in()], one.in_grad.data(), sizeof(float) * L.in()), 0)
        << "column " << c;
  }
}

TEST_P(MlpLayouts, ForwardMatchesReferenceForEveryColumn) {
  const nn::Layout L = GetParam() == 0 ? nn::agent_layout(54) : nn::connector_layout();
  const std::vector<double> p = random_vec(L.param_count(), 1, 0.3);
  const int cols = 7;
  std::vector<double> acts(L.activation_count() * cols);
  const std::vector<double> in = random_vec(L.in() * cols, 2, 1.0);
  std::copy(in.begin(), in.end(), acts.begin());
  nn::forward(L, p.data(), cols, acts.data());
  for (int c = 0; c < cols; ++c) {
    const std::vector<double> want =
        reference_forward(L, p, std::vector<double>(in.begin() + c * L.in(), in.begin() + (c + 1) * L.in()));
    for (int o = 0; o < L.out(); ++o)
      EXPECT_NEAR(acts[L.activation_offset(L.n_layers()) * cols + c * L.out() + o], want[o], 1e-14);
  }
}

TEST_P(MlpLayouts, BackwardMatchesCentralDifferences) {
  const nn::Layout L = GetParam() == 0 ? nn::agent_layout(54) : nn::connector_layout();
  const std::vector<double> p = random_vec(L.param_count(), 3, 0.3);
  const int cols = 3;
  const std::vector<double> in = random_vec(L.in() * cols, 4, 1.0);
  const std::vector<double> wout = random_vec(L.out() * cols, 5, 1.0);  // loss = Σ wout · y
  auto loss = [&](const std::vector<double>& pp, const std::vector<double>& xx) {
    std::vector<double> acts(L.activation_count() * cols);
    std::copy(xx.begin(), xx.end(), acts.begin());
    nn::forward(L, pp.data(), cols, acts.data());
    double s = 0;
    for (int q = 0; q < L.out() * cols; ++q) s += wout[q] * acts[L.activation_offset(L.n_layers()) * cols + q];
    return s;
  };
  std::vector<double> acts(L.activation_count() * cols);
  std::copy(in.begin(), in.end(), acts.begin());
  nn::forward(L, p.data(), cols, acts.data());
  std::vector<double> gp(L.param_count(), 0.0), gx(L.in() * cols), scratch(L.scratch_count() * cols);
  nn::backward(L, p.data(), cols, acts.data(), wout.data(), gp.data(), gx.data(), scratch.data());
  const double eps = 1e-6;
  // every bias and a spread of weights, and every input
  for (int q = 0; q < L.param_count(); q += (q % 7 == 0 ? 1 : 13)) {
    std::vector<double> pp = p, pm = p;
    pp[q] += eps;
    pm[q] -= eps;
    const double num = (loss(pp, in) - loss(pm, in)) / (2 * eps);
    ASSERT_NEAR(gp[q], num, 1e-7 * std::max(1.0, std::abs(num))) << "parameter " << q;
  }
  for (int q = 0; q < L.in() * cols; ++q) {
    std::vector<double> xp = in, xm = in;
    xp[q] += eps;
    xm[q] -= eps;
    const double num = (loss(p, xp) - loss(p, xm)) / (2 * eps);
    ASSERT_NEAR(gx[q], num, 1e-7 * std::max(1.0, std::abs(num))) << "input " << q;
  }
}

INSTANTIATE_TEST_SUITE_P(AgentAndConnector, MlpLayouts, ::testing::Values(0, 1),
                         [](const auto& info) { return info.param == 0 ? "agent" : "connector"; });

}  // namespace
}  // namespace divcoll
