// the MLP's public calls (nn/mlp.hpp): the layout, the packing, and each kernel call passed to the copy of the
// kernels of the path in use (nn/kernel_path.hpp; the kernels and why they are written as they are:
// nn/mlp_kernels.inc). This file is compiled for the build's instruction set, like the rest of the program.
#include "nn/mlp.hpp"

#include <algorithm>
#include <vector>

#include "nn/kernels.hpp"

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
Layout joint_connector_layout() { return Layout{{55, 32, 32, 5}}; }

template <class T>
int packed_count(const Layout& L) {
  const PackedLayer p = packed_layer<T>(L, L.n_layers() - 1);
  return static_cast<int>(p.w + static_cast<size_t>(p.out) * p.inp);
}

template <class T>
void pack(const Layout& L, const double* params, T* packed) {
  std::fill(packed, packed + packed_count<T>(L), T(0));
  for (int l = 0; l < L.n_layers(); ++l) {
    const PackedLayer p = packed_layer<T>(L, l);
    const double* W = params + L.weight_offset(l);
    const double* b = params + L.bias_offset(l);
    for (int o = 0; o < p.out; ++o) {
      packed[p.b + o] = static_cast<T>(b[o]);
      for (int i = 0; i < p.in; ++i) {
        packed[p.wt + static_cast<size_t>(i) * p.outp + o] = static_cast<T>(W[static_cast<size_t>(o) * p.in + i]);
        packed[p.w + static_cast<size_t>(o) * p.inp + i] = static_cast<T>(W[static_cast<size_t>(o) * p.in + i]);
      }
    }
  }
}

namespace {
template <class T>
const Kernels<T>& kernels_of(KernelPath p) {
  auto pick = [](const Kernels<double>& d, const Kernels<float>& f) -> const Kernels<T>& {
    if constexpr (sizeof(T) == sizeof(double)) return (void)f, d;
    else return (void)d, f;
  };
  switch (p) {
#if defined(__x86_64__)
    case KernelPath::avx2: return pick(isa_avx2::kernels_double(), isa_avx2::kernels_float());
    case KernelPath::avx512: return pick(isa_avx512::kernels_double(), isa_avx512::kernels_float());
#elif defined(__aarch64__)
    case KernelPath::neon: return pick(isa_neon::kernels_double(), isa_neon::kernels_float());
#endif
    default: return pick(isa_generic::kernels_double(), isa_generic::kernels_float());
  }
}
template <class T>
const Kernels<T>& active() { return kernels_of<T>(kernel_path()); }
}  // namespace

template <class T>
void tanh_inplace(T* p, int n) { active<T>().tanh_inplace(p, n); }

template <class T>
void forward_packed(const Layout& L, const T* packed, int cols, T* acts) {
  active<T>().forward_packed(L, packed, cols, acts);
}

template <class T>
void forward_packed_nets(const Layout& L, const T* packed, size_t packed_stride, int n, T* acts) {
  active<T>().forward_packed_nets(L, packed, packed_stride, n, acts);
}

template <class T>
void backward_packed(const Layout& L, const T* packed, int cols, const T* acts, const T* out_grad, T* param_grad,
                     T* in_grad, T* scratch) {
  active<T>().backward_packed(L, packed, cols, acts, out_grad, param_grad, in_grad, scratch);
}

void forward(const Layout& L, const double* params, int cols, double* acts) {
  std::vector<double> packed(packed_count(L));
  pack(L, params, packed.data());
  forward_packed(L, packed.data(), cols, acts);
}

void backward(const Layout& L, const double* params, int cols, const double* acts, const double* out_grad,
              double* param_grad, double* in_grad, double* scratch) {
  std::vector<double> packed(packed_count(L));
  pack(L, params, packed.data());
  backward_packed(L, packed.data(), cols, acts, out_grad, param_grad, in_grad, scratch);
}

// the two instantiations: double (the engine) and float
#define DIVCOLL_NN_INSTANTIATE(T)                                                                               \
  template int packed_count<T>(const Layout&);                                                                 \
  template void pack<T>(const Layout&, const double*, T*);                                                     \
  template void tanh_inplace<T>(T*, int);                                                                      \
  template void forward_packed<T>(const Layout&, const T*, int, T*);                                           \
  template void forward_packed_nets<T>(const Layout&, const T*, size_t, int, T*);                              \
  template void backward_packed<T>(const Layout&, const T*, int, const T*, const T*, T*, T*, T*);
DIVCOLL_NN_INSTANTIATE(double)
DIVCOLL_NN_INSTANTIATE(float)
#undef DIVCOLL_NN_INSTANTIATE

}  // namespace divcoll::nn
