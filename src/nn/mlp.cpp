// the MLP with a fixed order of every sum, on packed weights.
//
// Why not Eigen here: Eigen peels the unaligned head of a vectorised loop into scalar code and runs the
// rest in packets, and its scalar and packet exp (and its fused multiply-adds) round differently. The
// result then depends on where the heap put the parameter vector: two ranks, or a taped and an untaped
// run, would differ in the last bits. Every kernel below computes each output element with the same
// operations in the same order wherever the data lies: outputs are vector lanes (GCC vector extensions,
// elementwise only), multiply-adds are fused where the code says fmadd and nowhere else
// (-ffp-contract=off), and nothing is reassociated.
//
// Why packed: a layer as y = b + Σ_i Wᵀ[i, ·] x[i] keeps a column's 32 outputs in 4 (AVX-512) or 8
// registers and needs no horizontal sum; the old row-by-row dot products (8 partial sums reduced per
// output) spent most of their time in the reductions. Why fused: on this machine (Intel Xeon, two 512-bit
// FMA ports) a separate multiply and add take the same ports as one fma, so fusing halves the work of a
// layer. See the README's engine section for the measured gain of each.
#include "nn/mlp.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <immintrin.h>
#include <vector>

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

// kW doubles in one vector register (GCC/Clang vector extensions): 8 with AVX-512, else 4. Every
// operation is elementwise, so a lane gives the same bits as the scalar code would: nothing depends on
// alignment or on the lane. Multiply-adds are fused explicitly (fmadd), the same everywhere.
#if defined(__AVX512F__)
constexpr int kW = 8;
#else
constexpr int kW = 4;
#endif
using v4 = double __attribute__((vector_size(8 * kW)));
using v4i = long long __attribute__((vector_size(8 * kW)));

inline v4 loadw(const double* p) {
  v4 r;
  std::memcpy(&r, p, sizeof r);
  return r;
}
inline void storew(double* p, v4 v) { std::memcpy(p, &v, sizeof v); }
// stores NV vectors' first n values (n ≤ kW·NV) at p: whole vectors directly, the last partial one masked
// (or through a buffer without AVX-512); a call of memmove per column cost more than the copy itself
template <int NV>
inline void store_n(double* p, const v4* a, int n) {
  for (int v = 0; v < NV; ++v) {
    const int left = n - kW * v;
    if (left >= kW) {
      storew(p + kW * v, a[v]);
    } else if (left > 0) {
#if defined(__AVX512F__)
      _mm512_mask_storeu_pd(p + kW * v, static_cast<__mmask8>((1u << left) - 1), reinterpret_cast<__m512d>(a[v]));
#else
      double buf[kW];
      storew(buf, a[v]);
      for (int q = 0; q < left; ++q) p[kW * v + q] = buf[q];
#endif
    }
  }
}
// x in every lane, as a broadcast (from memory when x is a load: the load port does it). Not v4{} + x: that
// costs a scalar add and a register broadcast on the ports the fused multiply-adds need, per input value
inline v4 splat(double x) {
#if defined(__AVX512F__)
  return reinterpret_cast<v4>(_mm512_set1_pd(x));
#elif defined(__AVX__)
  return reinterpret_cast<v4>(_mm256_set1_pd(x));
#else
  v4 r;
  for (int k = 0; k < kW; ++k) r[k] = x;
  return r;
#endif
}
inline v4i bits(v4 x) { return reinterpret_cast<v4i>(x); }
inline v4 from_bits(v4i x) { return reinterpret_cast<v4>(x); }
constexpr int round_w(int n) { return (n + kW - 1) / kW * kW; }
constexpr int kBlock = 8 * kW;  // values per kernel call: up to 8 vectors
// a·b + c with one rounding
inline v4 fmadd(v4 a, v4 b, v4 c) {
#if defined(__AVX512F__)
  return reinterpret_cast<v4>(_mm512_fmadd_pd(reinterpret_cast<__m512d>(a), reinterpret_cast<__m512d>(b),
                                               reinterpret_cast<__m512d>(c)));
#elif defined(__FMA__)
  return reinterpret_cast<v4>(_mm256_fmadd_pd(reinterpret_cast<__m256d>(a), reinterpret_cast<__m256d>(b),
                                               reinterpret_cast<__m256d>(c)));
#else
  v4 r;
  for (int k = 0; k < kW; ++k) r[k] = std::fma(a[k], b[k], c[k]);
  return r;
#endif
}
inline v4 fmadd(v4 a, double b, v4 c) { return fmadd(a, splat(b), c); }

// tanh(x) = sign(x) (1 − e)/(1 + e), e = exp(−2|x|), with exp by Cody–Waite reduction and a degree-13
// Taylor polynomial on |r| ≤ ln2/2 (relative error < 2e-16); |x| is capped at 20, where tanh rounds to 1.
// NV vectors of kW lanes at once, each step over all NV before the next, so that the NV dependency
// chains (Horner, then the division) overlap instead of waiting on each other. NaN stays NaN, ±inf gives ±1.
template <int NV>
inline void tanh_n(v4* x) {
  const v4i sign = v4i{} + static_cast<long long>(0x8000000000000000ull);
  v4 big[NV], r[NV], p[NV];
  for (int v = 0; v < NV; ++v) {
    const v4 ax = from_bits(bits(x[v]) & ~sign);
    const v4 a = ax < splat(20.0) ? ax : splat(20.0);
    const v4 y = -2.0 * a;  // in [−40, 0]
    // k = round(y / ln2) by the 1.5·2^52 trick, kept in big's low mantissa bits
    big[v] = fmadd(y, 1.4426950408889634, splat(0x1.8p52));
    const v4 kf = big[v] - 0x1.8p52;
    r[v] = (y - kf * 6.93147180369123816490e-01) - kf * 1.90821492927058770002e-10;
    p[v] = splat(1.0 / 6227020800.0);
  }
  static constexpr double coef[] = {1.0 / 479001600.0, 1.0 / 39916800.0, 1.0 / 3628800.0, 1.0 / 362880.0,
                                    1.0 / 40320.0,     1.0 / 5040.0,     1.0 / 720.0,     1.0 / 120.0,
                                    1.0 / 24.0,        1.0 / 6.0,        0.5,             1.0,
                                    1.0};
  for (double c : coef)
    for (int v = 0; v < NV; ++v) p[v] = fmadd(p[v], r[v], splat(c));
  for (int v = 0; v < NV; ++v) {
    // 2^k for k in [−58, 0]
    const v4 scale = from_bits((bits(big[v]) - 0x4338000000000000ll + 1023ll) << 52);
    const v4 e = p[v] * scale;
    const v4 t = (1.0 - e) / (1.0 + e);
    const v4 s = from_bits(bits(t) | (bits(x[v]) & sign));
    x[v] = x[v] == x[v] ? s : x[v];
  }
}

// one layer for G columns at once, outputs [o0, o0 + kW·NV) of a packed layer: per column g,
// z = b + Σ_i Wᵀ[i, ·] x[i], the sum over i in two partial sums (even and odd i) added at the end, then
// y = tanh(z) if TANH (else y = z, for the caller to take the tanh of several columns at once); n_out (≤ kW·NV)
// outputs are stored. Each column has its own weights Wt[g], b[g] (one agent's network each) or all share one
// (the connector springs): the columns' chains are independent and interleaved, so that one column's layer and
// tanh fill the other's latency; each output is computed with the same operations in the same order as alone.
template <int NV, int G, bool TANH>
inline void layer_forward_g(const double* const* Wt, int ld, const double* const* b, int in, const double* const* x,
                            double* const* y, int n_out) {
  v4 a[G * NV], c[G * NV];
  for (int g = 0; g < G; ++g)
    for (int v = 0; v < NV; ++v) a[g * NV + v] = loadw(b[g] + kW * v), c[g * NV + v] = v4{};
  int i = 0;
  for (; i + 2 <= in; i += 2)
    for (int g = 0; g < G; ++g) {
      const double* w0 = Wt[g] + static_cast<size_t>(i) * ld;
      const double* w1 = w0 + ld;
      const double x0 = x[g][i], x1 = x[g][i + 1];
      for (int v = 0; v < NV; ++v) {
        a[g * NV + v] = fmadd(loadw(w0 + kW * v), x0, a[g * NV + v]);
        c[g * NV + v] = fmadd(loadw(w1 + kW * v), x1, c[g * NV + v]);
      }
    }
  if (i < in)
    for (int g = 0; g < G; ++g)
      for (int v = 0; v < NV; ++v)
        a[g * NV + v] = fmadd(loadw(Wt[g] + static_cast<size_t>(i) * ld + kW * v), x[g][i], a[g * NV + v]);
  for (int v = 0; v < G * NV; ++v) a[v] += c[v];
  if constexpr (TANH) tanh_n<G * NV>(a);
  for (int g = 0; g < G; ++g) store_n<NV>(y[g], a + g * NV, n_out);
}
// as many of n columns as one call takes (up to 16 accumulators live: G·NV ≤ 8); returns how many it took
template <int NV, bool TANH>
inline int layer_forward_some(int n, const double* const* Wt, int ld, const double* const* b, int in,
                              const double* const* x, double* const* y, int n_out) {
  constexpr int GM = NV >= 5 ? 1 : 8 / NV;
  if constexpr (GM >= 8)
    if (n >= 8) return layer_forward_g<NV, 8, TANH>(Wt, ld, b, in, x, y, n_out), 8;
  if constexpr (GM >= 4)
    if (n >= 4) return layer_forward_g<NV, 4, TANH>(Wt, ld, b, in, x, y, n_out), 4;
  if constexpr (GM >= 2)
    if (n >= 2) return layer_forward_g<NV, 2, TANH>(Wt, ld, b, in, x, y, n_out), 2;
  return layer_forward_g<NV, 1, TANH>(Wt, ld, b, in, x, y, n_out), 1;
}
template <bool TANH>
inline int layer_forward_dispatch(int nv, int n, const double* const* Wt, int ld, const double* const* b, int in,
                                  const double* const* x, double* const* y, int n_out) {
  switch (nv) {
    case 1: return layer_forward_some<1, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 2: return layer_forward_some<2, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 3: return layer_forward_some<3, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 4: return layer_forward_some<4, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 5: return layer_forward_some<5, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 6: return layer_forward_some<6, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 7: return layer_forward_some<7, TANH>(n, Wt, ld, b, in, x, y, n_out);
    default: return layer_forward_some<8, TANH>(n, Wt, ld, b, in, x, y, n_out);
  }
}

// one column of the input gradient, inputs [i0, i0 + kW·NV): d = Σ_o W[o, ·] g[o] (rows padded), the sum over
// o in two partial sums (even and odd o); n_in (≤ kW·NV) values are stored
template <int NV>
inline void layer_input_grad(const double* Wp, int ld, int out, const double* g, double* d, int n_in) {
  v4 a[NV], c[NV];
  for (int v = 0; v < NV; ++v) a[v] = v4{}, c[v] = v4{};
  int o = 0;
  for (; o + 2 <= out; o += 2) {
    const double* w0 = Wp + static_cast<size_t>(o) * ld;
    const double* w1 = w0 + ld;
    const double g0 = g[o], g1 = g[o + 1];
    for (int v = 0; v < NV; ++v) {
      a[v] = fmadd(loadw(w0 + kW * v), g0, a[v]);
      c[v] = fmadd(loadw(w1 + kW * v), g1, c[v]);
    }
  }
  if (o < out)
    for (int v = 0; v < NV; ++v) a[v] = fmadd(loadw(Wp + static_cast<size_t>(o) * ld + kW * v), g[o], a[v]);
  for (int v = 0; v < NV; ++v) a[v] += c[v];
  store_n<NV>(d, a, n_in);
}

// rows o of the weight gradient, inputs [i0, i0 + kW·NV) (whole vectors only): row += Σ_c g_c[o] x_c, the
// columns in order, the row kept in registers across the columns
template <int NV>
inline void weight_grad_row(double* row, const double* X, int in, const double* G, int out, int cols, int o) {
  v4 a[NV];
  for (int v = 0; v < NV; ++v) a[v] = loadw(row + kW * v);
  for (int c = 0; c < cols; ++c) {
    const double go = G[static_cast<size_t>(c) * out + o];
    const double* x = X + static_cast<size_t>(c) * in;
    for (int v = 0; v < NV; ++v) a[v] = fmadd(loadw(x + kW * v), go, a[v]);
  }
  for (int v = 0; v < NV; ++v) storew(row + kW * v, a[v]);
}

// runs KERNEL<nv>(args...) for nv = 1..8 (blocks of up to 32 values)
#define DIVCOLL_NN_DISPATCH(nv, KERNEL, ...)  \
  switch (nv) {                              \
    case 1: KERNEL<1>(__VA_ARGS__); break;   \
    case 2: KERNEL<2>(__VA_ARGS__); break;   \
    case 3: KERNEL<3>(__VA_ARGS__); break;   \
    case 4: KERNEL<4>(__VA_ARGS__); break;   \
    case 5: KERNEL<5>(__VA_ARGS__); break;   \
    case 6: KERNEL<6>(__VA_ARGS__); break;   \
    case 7: KERNEL<7>(__VA_ARGS__); break;   \
    default: KERNEL<8>(__VA_ARGS__); break;  \
  }

// packed layer l: Wᵀ (in × outp), b (outp), W (out × inp); outp, inp rounded up to 4, padding zero
struct PackedLayer {
  int in, out, inp, outp;
  size_t wt, b, w;  // offsets in the packed vector
};
PackedLayer packed_layer(const Layout& L, int l) {
  size_t off = 0;
  for (int k = 0;; ++k) {
    const int in = L.sizes[k], out = L.sizes[k + 1];
    const PackedLayer p{in, out, round_w(in), round_w(out), off, off + static_cast<size_t>(in) * round_w(out),
                        off + static_cast<size_t>(in + 1) * round_w(out)};
    if (k == l) return p;
    off = p.w + static_cast<size_t>(out) * p.inp;
  }
}

}  // namespace

int packed_count(const Layout& L) {
  const PackedLayer p = packed_layer(L, L.n_layers() - 1);
  return static_cast<int>(p.w + static_cast<size_t>(p.out) * p.inp);
}

void pack(const Layout& L, const double* params, double* packed) {
  std::fill(packed, packed + packed_count(L), 0.0);
  for (int l = 0; l < L.n_layers(); ++l) {
    const PackedLayer p = packed_layer(L, l);
    const double* W = params + L.weight_offset(l);
    const double* b = params + L.bias_offset(l);
    for (int o = 0; o < p.out; ++o) {
      packed[p.b + o] = b[o];
      for (int i = 0; i < p.in; ++i) {
        packed[p.wt + static_cast<size_t>(i) * p.outp + o] = W[static_cast<size_t>(o) * p.in + i];
        packed[p.w + static_cast<size_t>(o) * p.inp + i] = W[static_cast<size_t>(o) * p.in + i];
      }
    }
  }
}

void tanh_inplace(double* p, int n) {
  for (int i = 0; i < n; i += kW) {
    double buf[kW] = {};
    const int m = std::min(kW, n - i);
    std::copy(p + i, p + i + m, buf);
    v4 x = loadw(buf);
    tanh_n<1>(&x);
    storew(buf, x);
    std::copy(buf, buf + m, p + i);
  }
}

namespace {
// the layers of n single-column networks; net g's weights are packed + g·packed_stride and its activations of
// layer l are at act(g, l). A layer narrower than a vector (the connector's output) with shared weights
// takes its tanh over all columns at once afterwards (tanh is elementwise: the same bits either way).
template <class Act>
void forward_nets(const Layout& L, const double* packed, size_t packed_stride, int n, Act act, double* shared_y) {
  constexpr int kChunk = 8;
  for (int l = 0; l < L.n_layers(); ++l) {
    const PackedLayer p = packed_layer(L, l);
    const bool narrow = p.out < kW && shared_y && n > 1;
    for (int o0 = 0; o0 < p.out; o0 += kBlock) {
      const int no = std::min(kBlock, p.out - o0);
      const int nv = (no + kW - 1) / kW;
      for (int g0 = 0; g0 < n;) {
        const double* Wt[kChunk];
        const double* b[kChunk];
        const double* x[kChunk];
        double* y[kChunk];
        const int m = std::min(kChunk, n - g0);
        for (int g = 0; g < m; ++g) {
          const double* P = packed + (g0 + g) * packed_stride;
          Wt[g] = P + p.wt + o0;
          b[g] = P + p.b + o0;
          x[g] = act(g0 + g, l);
          y[g] = act(g0 + g, l + 1) + o0;
        }
        for (int g = 0; g < m;)
          g += narrow ? layer_forward_dispatch<false>(nv, m - g, Wt + g, p.outp, b + g, p.in, x + g, y + g, no)
                      : layer_forward_dispatch<true>(nv, m - g, Wt + g, p.outp, b + g, p.in, x + g, y + g, no);
        g0 += m;
      }
    }
    if (narrow) tanh_inplace(shared_y + static_cast<size_t>(L.activation_offset(l + 1)) * n, p.out * n);
  }
}
}  // namespace

void forward_packed(const Layout& L, const double* packed, int cols, double* acts) {
  forward_nets(
      L, packed, 0, cols,
      [&](int c, int l) { return acts + static_cast<size_t>(L.activation_offset(l)) * cols + static_cast<size_t>(c) * L.sizes[l]; },
      acts);
}

void forward_packed_nets(const Layout& L, const double* packed, size_t packed_stride, int n, double* acts) {
  const size_t na = L.activation_count();
  forward_nets(L, packed, packed_stride, n, [&](int g, int l) { return acts + g * na + L.activation_offset(l); },
               nullptr);
}

void forward(const Layout& L, const double* params, int cols, double* acts) {
  std::vector<double> packed(packed_count(L));
  pack(L, params, packed.data());
  forward_packed(L, packed.data(), cols, acts);
}

void backward_packed(const Layout& L, const double* packed, int cols, const double* acts, const double* out_grad,
                     double* param_grad, double* in_grad, double* scratch) {
  const int max_size = L.scratch_count() / 2;
  double* g_cur = scratch;                                          // gradient w.r.t. layer output
  double* g_prev = scratch + static_cast<size_t>(max_size) * cols;  // gradient w.r.t. layer input
  std::copy(out_grad, out_grad + static_cast<size_t>(L.out()) * cols, g_cur);
  for (int l = L.n_layers() - 1; l >= 0; --l) {
    const PackedLayer p = packed_layer(L, l);
    const int in = p.in, out = p.out;
    const double* X = acts + static_cast<size_t>(L.activation_offset(l)) * cols;
    const double* Y = acts + static_cast<size_t>(L.activation_offset(l + 1)) * cols;
    // through tanh: dz = dy (1 − y²)
    for (int q = 0; q < out * cols; ++q) g_cur[q] *= (1.0 - Y[q] * Y[q]);
    // parameters: dW += dz xᵀ, db += dz, summed over the columns in order
    if (param_grad) {
      double* gW = param_grad + L.weight_offset(l);
      double* gb = param_grad + L.bias_offset(l);
      const int in4 = in / kW * kW;
      for (int o = 0; o < out; ++o) {
        double* row = gW + static_cast<size_t>(o) * in;
        for (int i0 = 0; i0 < in4; i0 += kBlock) {
          const int nv = std::min(8, (in4 - i0) / kW);
          DIVCOLL_NN_DISPATCH(nv, weight_grad_row, row + i0, X + i0, in, g_cur, out, cols, o)
        }
        // the inputs past the last whole vector, and the bias, in registers across the columns (in order);
        // through memory each column's update waited on the previous one's store
        const int nt = in - in4;
        double bias = gb[o];
#if defined(__AVX512F__)
        const __mmask8 mk = static_cast<__mmask8>((1u << nt) - 1);
        __m512d tail = _mm512_maskz_loadu_pd(mk, row + in4);
        for (int c = 0; c < cols; ++c) {
          const double go = g_cur[static_cast<size_t>(c) * out + o];
          tail = _mm512_fmadd_pd(_mm512_maskz_loadu_pd(mk, X + static_cast<size_t>(c) * in + in4), _mm512_set1_pd(go), tail);
          bias += go;
        }
        _mm512_mask_storeu_pd(row + in4, mk, tail);
#else
        for (int c = 0; c < cols; ++c) {
          const double go = g_cur[static_cast<size_t>(c) * out + o];
          const double* x = X + static_cast<size_t>(c) * in;
          for (int i = in4; i < in; ++i) row[i] = std::fma(x[i], go, row[i]);
          bias += go;
        }
#endif
        gb[o] = bias;
      }
    }
    // input: dx = Wᵀ dz
    if (l == 0 && !in_grad) break;
    double* D = (l == 0) ? in_grad : g_prev;
    for (int c = 0; c < cols; ++c) {
      const double* g = g_cur + static_cast<size_t>(c) * out;
      double* d = D + static_cast<size_t>(c) * in;
      for (int i0 = 0; i0 < in; i0 += kBlock) {
        const int n = std::min(kBlock, in - i0);
        DIVCOLL_NN_DISPATCH((n + kW - 1) / kW, layer_input_grad, packed + p.w + i0, p.inp, out, g, d + i0, n)
      }
    }
    std::swap(g_cur, g_prev);
  }
}

void backward(const Layout& L, const double* params, int cols, const double* acts, const double* out_grad,
              double* param_grad, double* in_grad, double* scratch) {
  std::vector<double> packed(packed_count(L));
  pack(L, params, packed.data());
  backward_packed(L, packed.data(), cols, acts, out_grad, param_grad, in_grad, scratch);
}

}  // namespace divcoll::nn
