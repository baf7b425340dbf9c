// the MLP in plain loops with a fixed order of every sum.
//
// Why not Eigen here: Eigen peels the unaligned head of a vectorised loop into scalar code and runs the
// rest in packets, and its scalar and packet exp (and its fused multiply-adds) round differently. The
// result then depends on where the heap put the parameter vector: two ranks, or a taped and an untaped
// run, would differ in the last bits. Every loop below computes each output element with the same
// operations in the same order wherever the data lies; GCC vectorises them (-O3) without changing that,
// because -ffp-contract=off forbids fusing and nothing is reassociated.
#include "nn/mlp.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace divcoll::nn {

int Layout::param_count() const {
  int n = 0;
  for (int l = 0; l < n_layers(); ++l) n += sizes[l + 1] * sizes[l] + sizes[l + 1];
  return n;
}

int Layout::weight_offset(int layer) const {
  int n = 0;
  for (int l = 0; l < layer; ++l) n += sizes[l + 1] * sizes[l] + sizes[l + 1];
  return n;
}

int Layout::bias_offset(int layer) const { return weight_offset(layer) + sizes[layer + 1] * sizes[layer]; }

int Layout::activation_count() const {
  int n = 0;
  for (int s : sizes) n += s;
  return n;
}

int Layout::activation_offset(int l) const {
  int n = 0;
  for (int k = 0; k < l; ++k) n += sizes[k];
  return n;
}

int Layout::scratch_count() const { return 2 * *std::max_element(sizes.begin(), sizes.end()); }

Layout agent_layout(int n_inputs) { return Layout{{n_inputs, 32, 32, 21}}; }
Layout connector_layout() { return Layout{{11, 32, 32, 1}}; }

namespace {

// tanh(x) = sign(x) (1 − e)/(1 + e), e = exp(−2|x|), with exp by Cody–Waite reduction and a degree-13
// Taylor polynomial on |r| ≤ ln2/2 (relative error < 2e-16); |x| is capped at 20, where tanh rounds to 1
inline double tanh_one(double x) {
  const double a = std::min(std::fabs(x), 20.0);
  const double y = -2.0 * a;  // in [−40, 0]
  // k = round(y / ln2) by the 1.5·2^52 trick (vectorises, unlike floor), kept in big's low mantissa bits
  const double big = y * 1.4426950408889634 + 0x1.8p52;
  const double kf = big - 0x1.8p52;
  const double r = (y - kf * 6.93147180369123816490e-01) - kf * 1.90821492927058770002e-10;
  double p = 1.0 / 6227020800.0;
  p = p * r + 1.0 / 479001600.0;
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  // 2^k for k in [−58, 0]
  const double scale = std::bit_cast<double>((std::bit_cast<uint64_t>(big) - 0x4338000000000000ull + 1023ull) << 52);
  const double e = p * scale;
  const double t = (1.0 - e) / (1.0 + e);
  const double s = std::copysign(t, x);
  return x == x ? s : x;  // NaN stays NaN
}

// y = W x for a row-major (out × in) W: each row's dot product in 8 interleaved partial sums, summed in a
// fixed order, then the tail
inline void matvec(const double* W, int out, int in, const double* x, double* y) {
  const int in8 = in - in % 8;
  for (int o = 0; o < out; ++o) {
    const double* w = W + static_cast<size_t>(o) * in;
    double acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int i = 0; i < in8; i += 8)
      for (int l = 0; l < 8; ++l) acc[l] += w[i + l] * x[i + l];
    double s = ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
    for (int i = in8; i < in; ++i) s += w[i] * x[i];
    y[o] = s;
  }
}

}  // namespace

void tanh_inplace(double* p, int n) {
  for (int i = 0; i < n; ++i) p[i] = tanh_one(p[i]);
}

void forward(const Layout& L, const double* params, int cols, double* acts) {
  for (int l = 0; l < L.n_layers(); ++l) {
    const int in = L.sizes[l], out = L.sizes[l + 1];
    const double* W = params + L.weight_offset(l);
    const double* b = params + L.bias_offset(l);
    const double* X = acts + static_cast<size_t>(L.activation_offset(l)) * cols;
    double* Y = acts + static_cast<size_t>(L.activation_offset(l + 1)) * cols;
    // z = W x + b per column, then tanh
    for (int c = 0; c < cols; ++c) {
      double* y = Y + static_cast<size_t>(c) * out;
      matvec(W, out, in, X + static_cast<size_t>(c) * in, y);
      for (int o = 0; o < out; ++o) y[o] += b[o];
    }
    tanh_inplace(Y, out * cols);
  }
}

void backward(const Layout& L, const double* params, int cols, const double* acts, const double* out_grad,
              double* param_grad, double* in_grad, double* scratch) {
  const int max_size = L.scratch_count() / 2;
  double* g_cur = scratch;                                          // gradient w.r.t. layer output
  double* g_prev = scratch + static_cast<size_t>(max_size) * cols;  // gradient w.r.t. layer input
  std::copy(out_grad, out_grad + static_cast<size_t>(L.out()) * cols, g_cur);
  for (int l = L.n_layers() - 1; l >= 0; --l) {
    const int in = L.sizes[l], out = L.sizes[l + 1];
    const double* W = params + L.weight_offset(l);
    double* gW = param_grad + L.weight_offset(l);
    double* gb = param_grad + L.bias_offset(l);
    const double* X = acts + static_cast<size_t>(L.activation_offset(l)) * cols;
    const double* Y = acts + static_cast<size_t>(L.activation_offset(l + 1)) * cols;
    // through tanh: dz = dy (1 − y²)
    for (int q = 0; q < out * cols; ++q) g_cur[q] *= (1.0 - Y[q] * Y[q]);
    // parameters, column by column: dW += dz xᵀ, db += dz
    for (int c = 0; c < cols; ++c) {
      const double* g = g_cur + static_cast<size_t>(c) * out;
      const double* x = X + static_cast<size_t>(c) * in;
      for (int o = 0; o < out; ++o) {
        double* row = gW + static_cast<size_t>(o) * in;
        const double go = g[o];
        for (int i = 0; i < in; ++i) row[i] += go * x[i];
        gb[o] += go;
      }
    }
    // input: dx = Wᵀ dz, rows of W in order
    if (l == 0 && !in_grad) break;
    double* D = (l == 0) ? in_grad : g_prev;
    for (int c = 0; c < cols; ++c) {
      const double* g = g_cur + static_cast<size_t>(c) * out;
      double* d = D + static_cast<size_t>(c) * in;
      for (int i = 0; i < in; ++i) d[i] = 0;
      for (int o = 0; o < out; ++o) {
        const double* w = W + static_cast<size_t>(o) * in;
        const double go = g[o];
        for (int i = 0; i < in; ++i) d[i] += w[i] * go;
      }
    }
    std::swap(g_cur, g_prev);
  }
}

}  // namespace divcoll::nn
