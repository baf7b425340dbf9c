#include "nn/mlp.hpp"

#include <Eigen/Dense>
#include <algorithm>

namespace divcoll::nn {
namespace {
using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using ColMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor>;
}  // namespace

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

void tanh_inplace(double* p, int n) {
  Eigen::Map<Eigen::ArrayXd> a(p, n);
  a = 1.0 - 2.0 / ((2.0 * a).exp() + 1.0);
}

void forward(const Layout& L, const double* params, int cols, double* acts) {
  for (int l = 0; l < L.n_layers(); ++l) {
    const int in = L.sizes[l], out = L.sizes[l + 1];
    Eigen::Map<const RowMat> W(params + L.weight_offset(l), out, in);
    Eigen::Map<const Eigen::VectorXd> b(params + L.bias_offset(l), out);
    Eigen::Map<const ColMat> X(acts + L.activation_offset(l) * cols, in, cols);
    Eigen::Map<ColMat> Y(acts + L.activation_offset(l + 1) * cols, out, cols);
    // z = W x + b, then tanh
    if (cols == 1) {
      Y.col(0).noalias() = W * X.col(0);
      Y.col(0) += b;
    } else {
      Y.noalias() = W * X;
      Y.colwise() += b;
    }
    tanh_inplace(Y.data(), out * cols);
  }
}

void backward(const Layout& L, const double* params, int cols, const double* acts, const double* out_grad,
              double* param_grad, double* in_grad, double* scratch) {
  const int max_size = L.scratch_count() / 2;
  double* g_cur = scratch;                      // gradient w.r.t. layer l's output (post-tanh)
  double* g_prev = scratch + max_size * cols;   // gradient w.r.t. layer l's input
  std::copy(out_grad, out_grad + L.out() * cols, g_cur);
  for (int l = L.n_layers() - 1; l >= 0; --l) {
    const int in = L.sizes[l], out = L.sizes[l + 1];
    Eigen::Map<const RowMat> W(params + L.weight_offset(l), out, in);
    Eigen::Map<RowMat> gW(param_grad + L.weight_offset(l), out, in);
    Eigen::Map<Eigen::VectorXd> gb(param_grad + L.bias_offset(l), out);
    Eigen::Map<const ColMat> X(acts + L.activation_offset(l) * cols, in, cols);
    Eigen::Map<const ColMat> Y(acts + L.activation_offset(l + 1) * cols, out, cols);
    Eigen::Map<ColMat> G(g_cur, out, cols);
    // through tanh: dz = dy (1 − y²)
    G.array() *= (1.0 - Y.array().square());
    // parameter gradient: dW += dz xᵀ, db += Σ_cols dz
    if (cols == 1) {
      gW.noalias() += G.col(0) * X.col(0).transpose();
      gb += G.col(0);
    } else {
      gW.noalias() += G * X.transpose();
      for (int c = 0; c < cols; ++c) gb += G.col(c);
    }
    // input gradient: dx = Wᵀ dz
    if (l == 0 && !in_grad) break;
    double* dst = (l == 0) ? in_grad : g_prev;
    Eigen::Map<ColMat> D(dst, in, cols);
    if (cols == 1)
      D.col(0).noalias() = W.transpose() * G.col(0);
    else
      D.noalias() = W.transpose() * G;
    std::swap(g_cur, g_prev);
  }
}

}  // namespace divcoll::nn
