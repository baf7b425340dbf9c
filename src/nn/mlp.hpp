// the multilayer perceptron of both controllers (SPEC §4.3, §6.3) on one flat parameter vector.
//
// Layout of the parameter vector: per layer W (out × in, row-major) then b. The same vector is the
// genome, the gradient (same layout) and the MPI payload. Every layer is followed by tanh.
//
// Activations are kept per layer as a column-major (size × cols) block, so one call evaluates the
// network on `cols` inputs at once (the 5·C springs of the connectors of a collective share one weight
// set). The kernels read the weights in a packed copy (pack(), once per parameter vector): per layer
// Wᵀ (in × out rounded up to whole 64-byte blocks) for the forward pass, so that every output is a vector lane and a
// layer is a chain of broadcast-multiply-adds with no horizontal sums, and W with rows padded the same way for the
// input gradient. The kernels are those of the kernel path in use (nn/kernel_path.hpp); every path gives the same
// bits. With packed weights the caller owns every buffer: the *_packed calls
// allocate nothing; forward() and backward() on a plain parameter vector pack into a temporary first.
#pragma once

#include <cstddef>
#include <vector>

namespace divcoll::nn {

struct Layout {
  std::vector<int> sizes;  // input size, then each layer's output size

  int n_layers() const { return static_cast<int>(sizes.size()) - 1; }
  int in() const { return sizes.front(); }
  int out() const { return sizes.back(); }
  int param_count() const;
  int weight_offset(int layer) const;  // layer in [0, n_layers)
  int bias_offset(int layer) const;
  // doubles of the activation buffer for one column: input + every layer's output
  int activation_count() const;
  // offset (per column) of layer l's activations in the activation buffer; l = 0 is the input
  int activation_offset(int l) const;
  // doubles of scratch needed by backward for one column
  int scratch_count() const;
};

Layout agent_layout(int n_inputs);  // n_inputs → 32 → 32 → 21
Layout connector_layout();          // 11 → 32 → 32 → 1
Layout joint_connector_layout();    // 55 → 32 → 32 → 5: one network reading all five springs of a connector

// The kernels below are templates on the scalar T, instantiated for double (the engine's precision, SPEC §10)
// and float (a float path's building block: the same algorithms with twice the lanes per vector, a tanh of its
// own precision, and parameters rounded to float by pack(); measured in `divcoll bench`, not used by the engine).

// values of T in the packed copy of a parameter vector
template <class T = double>
int packed_count(const Layout& L);
// params (param_count(), always double) → packed (packed_count<T>())
template <class T>
void pack(const Layout& L, const double* params, T* packed);

// acts: activation buffer of activation_count()*cols values, laid out as blocks per layer, each block
// (size_l × cols) column-major; the caller fills the input block (l = 0), forward fills the rest.
template <class T>
void forward_packed(const Layout& L, const T* packed, int cols, T* acts);
void forward(const Layout& L, const double* params, int cols, double* acts);
// n networks of the same layout, one column each, with their own weights (packed + g·packed_stride) and their
// own activation buffers (acts + g·activation_count()); the same bits as n calls of forward_packed, but the
// networks' dependency chains are interleaved (two agents' layers fill each other's latency)
template <class T>
void forward_packed_nets(const Layout& L, const T* packed, size_t packed_stride, int n, T* acts);

// backward from the gradient of the loss w.r.t. the outputs (post-tanh), out_grad (out × cols).
// adds the parameter gradient into param_grad (param_count()) and, when in_grad is not null, writes the
// gradient w.r.t. the input block into in_grad (in × cols). scratch: scratch_count()*cols values.
// param_grad may be null: no parameter gradient is computed (frozen weights; that is a third of the work)
template <class T>
void backward_packed(const Layout& L, const T* packed, int cols, const T* acts, const T* out_grad, T* param_grad,
                     T* in_grad, T* scratch);
void backward(const Layout& L, const double* params, int cols, const double* acts, const double* out_grad,
              double* param_grad, double* in_grad, double* scratch);

// tanh over n values: the same bits for a value wherever it lies in memory (absolute error < 3e-16 in double,
// < 1.2e-7 in float)
template <class T>
void tanh_inplace(T* p, int n);

}  // namespace divcoll::nn
