// the MLP's kernel paths: one copy of the kernels per instruction set (nn/mlp_kernels.inc), behind one table of
// function pointers each, and the packed layout they all read. Internal to src/nn.
#pragma once

#include <cstddef>

#include "nn/kernel_path.hpp"
#include "nn/mlp.hpp"

namespace divcoll::nn {

// every packed row and column is padded to whole 64-byte blocks (the widest vector, AVX-512's): one packed layout for
// every path, so a packed parameter vector reads the same whichever path reads it, and padding only adds zero lanes
// whose outputs are never stored
inline constexpr int kPackBytes = 64;

template <class T>
struct Kernels {
  void (*forward_packed)(const Layout& L, const T* packed, int cols, T* acts);
  void (*forward_packed_nets)(const Layout& L, const T* packed, size_t packed_stride, int n, T* acts);
  void (*backward_packed)(const Layout& L, const T* packed, int cols, const T* acts, const T* out_grad, T* param_grad,
                          T* in_grad, T* scratch);
  void (*tanh_inplace)(T* p, int n);
};

// the kernels of one path (each defined by its own file, compiled for its instruction set)
#define DIVCOLL_NN_DECLARE_PATH(ns)           \
  namespace ns {                              \
  const Kernels<double>& kernels_double();    \
  const Kernels<float>& kernels_float();      \
  }
DIVCOLL_NN_DECLARE_PATH(isa_generic)
DIVCOLL_NN_DECLARE_PATH(isa_avx2)
DIVCOLL_NN_DECLARE_PATH(isa_avx512)
DIVCOLL_NN_DECLARE_PATH(isa_neon)
#undef DIVCOLL_NN_DECLARE_PATH

// internal linkage: each file that computes the layout has its own copy, compiled for its own instruction set
namespace {

// packed layer l: Wᵀ (in × outp), b (outp), W (out × inp); outp, inp rounded up to whole 64-byte blocks of T,
// padding zero
struct PackedLayer {
  int in, out, inp, outp;
  size_t wt, b, w;  // offsets in the packed vector
};
template <class T>
constexpr int round_pack(int n) {
  constexpr int w = kPackBytes / static_cast<int>(sizeof(T));
  return (n + w - 1) / w * w;
}
template <class T>
PackedLayer packed_layer(const Layout& L, int l) {
  size_t off = 0;
  for (int k = 0;; ++k) {
    const int in = L.sizes[k], out = L.sizes[k + 1];
    const PackedLayer p{in,  out, round_pack<T>(in), round_pack<T>(out), off,
                        off + static_cast<size_t>(in) * round_pack<T>(out),
                        off + static_cast<size_t>(in + 1) * round_pack<T>(out)};
    if (k == l) return p;
    off = p.w + static_cast<size_t>(out) * p.inp;
  }
}

}  // namespace

}  // namespace divcoll::nn
