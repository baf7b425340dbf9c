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
// registers of doubles (2 or 4 of floats) and needs no horizontal sum; the old row-by-row dot products (8 partial sums reduced per
// output) spent most of their time in the reductions. Why fused: on this machine (Intel Xeon, two 512-bit
// FMA ports) a separate multiply and add take the same ports as one fma, so fusing halves the work of a
// layer. jobs/BENCHMARKS.md gives the measured gain of each.
//
// Every kernel is a template on the scalar T, instantiated for double (the engine) and float (measured by
// `divcoll bench` against double, for a float path; mlp.hpp). The double instantiation is the code it was before
// the templates, operation for operation (the tiny golden digest is unchanged).
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
Layout joint_connector_layout() { return Layout{{55, 32, 32, 5}}; }

namespace {

// Simd<T>::W values of T in one vector register (GCC/Clang vector extensions): 64 bytes with AVX-512, else 32.
// Every operation is elementwise, so a lane gives the same bits as the scalar code would: nothing depends on
// alignment or on the lane. Multiply-adds are fused explicitly (fmadd), the same everywhere. Double is the
// engine's precision (SPEC §10); float is the kernels' second instantiation, for the float path's measurements.
#if defined(__AVX512F__)
constexpr int kVectorBytes = 64;
#else
constexpr int kVectorBytes = 32;
#endif
// (GCC takes vector_size only on a non-dependent type: one specialisation per T)
template <class T>
struct Simd;
template <>
struct Simd<double> {
  static constexpr int W = kVectorBytes / 8;
  using I = long long;  // an integer of the value's width
  using V = double __attribute__((vector_size(kVectorBytes)));
  using VI = long long __attribute__((vector_size(kVectorBytes)));
};
template <>
struct Simd<float> {
  static constexpr int W = kVectorBytes / 4;
  using I = int;
  using V = float __attribute__((vector_size(kVectorBytes)));
  using VI = int __attribute__((vector_size(kVectorBytes)));
};
template <class T>
using Vec = typename Simd<T>::V;
template <class T>
using VecI = typename Simd<T>::VI;
template <class T>
constexpr int kW = Simd<T>::W;

template <class T>
inline Vec<T> loadw(const T* p) {
  Vec<T> r;
  std::memcpy(&r, p, sizeof r);
  return r;
}
template <class T>
inline void storew(T* p, Vec<T> v) { std::memcpy(p, &v, sizeof v); }
#if defined(__AVX512F__)
// the first n (< W) lanes of a vector, as an AVX-512 mask
template <class T>
inline auto lane_mask(int n) {
  if constexpr (sizeof(T) == 8) return static_cast<__mmask8>((1u << n) - 1);
  else return static_cast<__mmask16>((1u << n) - 1);
}
template <class T>
inline Vec<T> load_masked(const T* p, int n) {  // lanes past n read as 0 (and are not read)
  if constexpr (sizeof(T) == 8) return reinterpret_cast<Vec<T>>(_mm512_maskz_loadu_pd(lane_mask<T>(n), p));
  else return reinterpret_cast<Vec<T>>(_mm512_maskz_loadu_ps(lane_mask<T>(n), p));
}
template <class T>
inline void store_masked(T* p, int n, Vec<T> v) {
  if constexpr (sizeof(T) == 8) _mm512_mask_storeu_pd(p, lane_mask<T>(n), reinterpret_cast<__m512d>(v));
  else _mm512_mask_storeu_ps(p, lane_mask<T>(n), reinterpret_cast<__m512>(v));
}
#endif
// stores NV vectors' first n values (n ≤ W·NV) at p: whole vectors directly, the last partial one masked
// (or through a buffer without AVX-512); a call of memmove per column cost more than the copy itself
template <class T, int NV>
inline void store_n(T* p, const Vec<T>* a, int n) {
  constexpr int w = kW<T>;
  for (int v = 0; v < NV; ++v) {
    const int left = n - w * v;
    if (left >= w) {
      storew(p + w * v, a[v]);
    } else if (left > 0) {
#if defined(__AVX512F__)
      store_masked<T>(p + w * v, left, a[v]);
#else
      T buf[w];
      storew(buf, a[v]);
      for (int q = 0; q < left; ++q) p[w * v + q] = buf[q];
#endif
    }
  }
}
// x in every lane, as a broadcast (from memory when x is a load: the load port does it). Not Vec{} + x: that
// costs a scalar add and a register broadcast on the ports the fused multiply-adds need, per input value
template <class T>
inline Vec<T> splat(T x) {
#if defined(__AVX512F__)
  if constexpr (sizeof(T) == 8) return reinterpret_cast<Vec<T>>(_mm512_set1_pd(x));
  else return reinterpret_cast<Vec<T>>(_mm512_set1_ps(x));
#elif defined(__AVX__)
  if constexpr (sizeof(T) == 8) return reinterpret_cast<Vec<T>>(_mm256_set1_pd(x));
  else return reinterpret_cast<Vec<T>>(_mm256_set1_ps(x));
#else
  Vec<T> r;
  for (int k = 0; k < kW<T>; ++k) r[k] = x;
  return r;
#endif
}
template <class T>
inline VecI<T> bits(Vec<T> x) { return reinterpret_cast<VecI<T>>(x); }
template <class T>
inline Vec<T> from_bits(VecI<T> x) { return reinterpret_cast<Vec<T>>(x); }
template <class T>
constexpr int round_w(int n) { return (n + kW<T> - 1) / kW<T> * kW<T>; }
template <class T>
constexpr int kBlock = 8 * kW<T>;  // values per kernel call: up to 8 vectors
// a·b + c with one rounding
template <class T>
inline Vec<T> fmadd(Vec<T> a, Vec<T> b, Vec<T> c) {
#if defined(__AVX512F__)
  if constexpr (sizeof(T) == 8)
    return reinterpret_cast<Vec<T>>(_mm512_fmadd_pd(reinterpret_cast<__m512d>(a), reinterpret_cast<__m512d>(b),
                                                    reinterpret_cast<__m512d>(c)));
  else
    return reinterpret_cast<Vec<T>>(_mm512_fmadd_ps(reinterpret_cast<__m512>(a), reinterpret_cast<__m512>(b),
                                                    reinterpret_cast<__m512>(c)));
#elif defined(__FMA__)
  if constexpr (sizeof(T) == 8)
    return reinterpret_cast<Vec<T>>(_mm256_fmadd_pd(reinterpret_cast<__m256d>(a), reinterpret_cast<__m256d>(b),
                                                    reinterpret_cast<__m256d>(c)));
  else
    return reinterpret_cast<Vec<T>>(_mm256_fmadd_ps(reinterpret_cast<__m256>(a), reinterpret_cast<__m256>(b),
                                                    reinterpret_cast<__m256>(c)));
#else
  Vec<T> r;
  for (int k = 0; k < kW<T>; ++k) r[k] = std::fma(a[k], b[k], c[k]);
  return r;
#endif
}
template <class T>
inline Vec<T> fmadd(Vec<T> a, T b, Vec<T> c) { return fmadd<T>(a, splat<T>(b), c); }

// tanh(x) = sign(x) (1 − e)/(1 + e), e = exp(−2|x|), with exp by Cody–Waite reduction and a Taylor polynomial
// on |r| ≤ ln2/2. Double: degree 13 (relative error < 2e-16), |x| capped at 20, where tanh rounds to 1. Float:
// degree 7 (< 6e-9), |x| capped at 10. NV vectors of W lanes at once, each step over all NV before the next, so
// that the NV dependency chains (Horner, then the division) overlap instead of waiting on each other. NaN stays
// NaN, ±inf gives ±1.
template <class T, int NV>
inline void tanh_n(Vec<T>* x) {
  using V = Vec<T>;
  using VI = VecI<T>;
  using I = typename Simd<T>::I;
  constexpr bool dbl = sizeof(T) == 8;
  constexpr int mant = dbl ? 52 : 23;                     // mantissa bits
  constexpr T shifter = dbl ? T(0x1.8p52) : T(0x1.8p23);  // 1.5·2^mant: adding it rounds to an integer
  constexpr I shifter_bits = dbl ? I(0x4338000000000000ll) : I(0x4B400000);
  constexpr I bias = dbl ? 1023 : 127;
  constexpr T cap = dbl ? T(20.0) : T(10.0);
  constexpr T ln2_hi = dbl ? T(6.93147180369123816490e-01) : T(0x1.62e4p-1f);
  constexpr T ln2_lo = dbl ? T(1.90821492927058770002e-10) : T(0x1.7f7d1cp-20f);
  const VI sign = VI{} + static_cast<I>(I(1) << (8 * sizeof(T) - 1));
  V big[NV], r[NV], p[NV];
  for (int v = 0; v < NV; ++v) {
    const V ax = from_bits<T>(bits<T>(x[v]) & ~sign);
    const V a = ax < splat<T>(cap) ? ax : splat<T>(cap);
    const V y = T(-2.0) * a;  // in [−2 cap, 0]
    // k = round(y / ln2) by the 1.5·2^mant trick, kept in big's low mantissa bits
    big[v] = fmadd<T>(y, T(1.4426950408889634), splat<T>(shifter));
    const V kf = big[v] - shifter;
    r[v] = (y - kf * ln2_hi) - kf * ln2_lo;
    p[v] = splat<T>(dbl ? T(1.0 / 6227020800.0) : T(1.0 / 5040.0));
  }
  if constexpr (dbl) {
    static constexpr T coef[] = {1.0 / 479001600.0, 1.0 / 39916800.0, 1.0 / 3628800.0, 1.0 / 362880.0,
                                 1.0 / 40320.0,     1.0 / 5040.0,     1.0 / 720.0,     1.0 / 120.0,
                                 1.0 / 24.0,        1.0 / 6.0,        0.5,             1.0,
                                 1.0};
    for (T c : coef)
      for (int v = 0; v < NV; ++v) p[v] = fmadd<T>(p[v], r[v], splat<T>(c));
  } else {
    static constexpr T coef[] = {1.0f / 720.0f, 1.0f / 120.0f, 1.0f / 24.0f, 1.0f / 6.0f, 0.5f, 1.0f, 1.0f};
    for (T c : coef)
      for (int v = 0; v < NV; ++v) p[v] = fmadd<T>(p[v], r[v], splat<T>(c));
  }
  for (int v = 0; v < NV; ++v) {
    // 2^k for k in [−2 cap / ln2 − 1, 0]
    const V scale = from_bits<T>((bits<T>(big[v]) - shifter_bits + bias) << mant);
    const V e = p[v] * scale;
    const V t = (T(1.0) - e) / (T(1.0) + e);
    const V s = from_bits<T>(bits<T>(t) | (bits<T>(x[v]) & sign));
    x[v] = x[v] == x[v] ? s : x[v];
  }
}

// one layer for G columns at once, outputs [o0, o0 + W·NV) of a packed layer: per column g,
// z = b + Σ_i Wᵀ[i, ·] x[i], the sum over i in two partial sums (even and odd i) added at the end, then
// y = tanh(z) if TANH (else y = z, for the caller to take the tanh of several columns at once); n_out (≤ W·NV)
// outputs are stored. Each column has its own weights Wt[g], b[g] (one agent's network each) or all share one
// (the connector springs): the columns' chains are independent and interleaved, so that one column's layer and
// tanh fill the other's latency; each output is computed with the same operations in the same order as alone.
template <class T, int NV, int G, bool TANH>
inline void layer_forward_g(const T* const* Wt, int ld, const T* const* b, int in, const T* const* x, T* const* y,
                            int n_out) {
  constexpr int w = kW<T>;
  Vec<T> a[G * NV], c[G * NV];
  for (int g = 0; g < G; ++g)
    for (int v = 0; v < NV; ++v) a[g * NV + v] = loadw(b[g] + w * v), c[g * NV + v] = Vec<T>{};
  int i = 0;
  for (; i + 2 <= in; i += 2)
    for (int g = 0; g < G; ++g) {
      const T* w0 = Wt[g] + static_cast<size_t>(i) * ld;
      const T* w1 = w0 + ld;
      const T x0 = x[g][i], x1 = x[g][i + 1];
      for (int v = 0; v < NV; ++v) {
        a[g * NV + v] = fmadd<T>(loadw(w0 + w * v), x0, a[g * NV + v]);
        c[g * NV + v] = fmadd<T>(loadw(w1 + w * v), x1, c[g * NV + v]);
      }
    }
  if (i < in)
    for (int g = 0; g < G; ++g)
      for (int v = 0; v < NV; ++v)
        a[g * NV + v] = fmadd<T>(loadw(Wt[g] + static_cast<size_t>(i) * ld + w * v), x[g][i], a[g * NV + v]);
  for (int v = 0; v < G * NV; ++v) a[v] += c[v];
  if constexpr (TANH) tanh_n<T, G * NV>(a);
  for (int g = 0; g < G; ++g) store_n<T, NV>(y[g], a + g * NV, n_out);
}
// as many of n columns as one call takes (up to 16 accumulators live: G·NV ≤ 8); returns how many it took
template <class T, int NV, bool TANH>
inline int layer_forward_some(int n, const T* const* Wt, int ld, const T* const* b, int in, const T* const* x,
                              T* const* y, int n_out) {
  constexpr int GM = NV >= 5 ? 1 : 8 / NV;
  if constexpr (GM >= 8)
    if (n >= 8) return layer_forward_g<T, NV, 8, TANH>(Wt, ld, b, in, x, y, n_out), 8;
  if constexpr (GM >= 4)
    if (n >= 4) return layer_forward_g<T, NV, 4, TANH>(Wt, ld, b, in, x, y, n_out), 4;
  if constexpr (GM >= 2)
    if (n >= 2) return layer_forward_g<T, NV, 2, TANH>(Wt, ld, b, in, x, y, n_out), 2;
  return layer_forward_g<T, NV, 1, TANH>(Wt, ld, b, in, x, y, n_out), 1;
}
template <class T, bool TANH>
inline int layer_forward_dispatch(int nv, int n, const T* const* Wt, int ld, const T* const* b, int in,
                                  const T* const* x, T* const* y, int n_out) {
  switch (nv) {
    case 1: return layer_forward_some<T, 1, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 2: return layer_forward_some<T, 2, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 3: return layer_forward_some<T, 3, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 4: return layer_forward_some<T, 4, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 5: return layer_forward_some<T, 5, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 6: return layer_forward_some<T, 6, TANH>(n, Wt, ld, b, in, x, y, n_out);
    case 7: return layer_forward_some<T, 7, TANH>(n, Wt, ld, b, in, x, y, n_out);
    default: return layer_forward_some<T, 8, TANH>(n, Wt, ld, b, in, x, y, n_out);
  }
}

// one column of the input gradient, inputs [i0, i0 + W·NV): d = Σ_o W[o, ·] g[o] (rows padded), the sum over
// o in two partial sums (even and odd o); n_in (≤ W·NV) values are stored
template <class T, int NV>
inline void layer_input_grad(const T* Wp, int ld, int out, const T* g, T* d, int n_in) {
  constexpr int w = kW<T>;
  Vec<T> a[NV], c[NV];
  for (int v = 0; v < NV; ++v) a[v] = Vec<T>{}, c[v] = Vec<T>{};
  int o = 0;
  for (; o + 2 <= out; o += 2) {
    const T* w0 = Wp + static_cast<size_t>(o) * ld;
    const T* w1 = w0 + ld;
    const T g0 = g[o], g1 = g[o + 1];
    for (int v = 0; v < NV; ++v) {
      a[v] = fmadd<T>(loadw(w0 + w * v), g0, a[v]);
      c[v] = fmadd<T>(loadw(w1 + w * v), g1, c[v]);
    }
  }
  if (o < out)
    for (int v = 0; v < NV; ++v) a[v] = fmadd<T>(loadw(Wp + static_cast<size_t>(o) * ld + w * v), g[o], a[v]);
  for (int v = 0; v < NV; ++v) a[v] += c[v];
  store_n<T, NV>(d, a, n_in);
}

// rows o of the weight gradient, inputs [i0, i0 + W·NV) (whole vectors only): row += Σ_c g_c[o] x_c, the
// columns in order, the row kept in registers across the columns
template <class T, int NV>
inline void weight_grad_row(T* row, const T* X, int in, const T* G, int out, int cols, int o) {
  constexpr int w = kW<T>;
  Vec<T> a[NV];
  for (int v = 0; v < NV; ++v) a[v] = loadw(row + w * v);
  for (int c = 0; c < cols; ++c) {
    const T go = G[static_cast<size_t>(c) * out + o];
    const T* x = X + static_cast<size_t>(c) * in;
    for (int v = 0; v < NV; ++v) a[v] = fmadd<T>(loadw(x + w * v), go, a[v]);
  }
  for (int v = 0; v < NV; ++v) storew(row + w * v, a[v]);
}

// runs KERNEL<T, nv>(args...) for nv = 1..8 (blocks of up to 8 vectors)
#define DIVCOLL_NN_DISPATCH(T, nv, KERNEL, ...) \
  switch (nv) {                                 \
    case 1: KERNEL<T, 1>(__VA_ARGS__); break;   \
    case 2: KERNEL<T, 2>(__VA_ARGS__); break;   \
    case 3: KERNEL<T, 3>(__VA_ARGS__); break;   \
    case 4: KERNEL<T, 4>(__VA_ARGS__); break;   \
    case 5: KERNEL<T, 5>(__VA_ARGS__); break;   \
    case 6: KERNEL<T, 6>(__VA_ARGS__); break;   \
    case 7: KERNEL<T, 7>(__VA_ARGS__); break;   \
    default: KERNEL<T, 8>(__VA_ARGS__); break;  \
  }

// packed layer l: Wᵀ (in × outp), b (outp), W (out × inp); outp, inp rounded up to whole vectors of T, padding zero
struct PackedLayer {
  int in, out, inp, outp;
  size_t wt, b, w;  // offsets in the packed vector
};
template <class T>
PackedLayer packed_layer(const Layout& L, int l) {
  size_t off = 0;
  for (int k = 0;; ++k) {
    const int in = L.sizes[k], out = L.sizes[k + 1];
    const PackedLayer p{in, out, round_w<T>(in), round_w<T>(out), off, off + static_cast<size_t>(in) * round_w<T>(out),
                        off + static_cast<size_t>(in + 1) * round_w<T>(out)};
    if (k == l) return p;
    off = p.w + static_cast<size_t>(out) * p.inp;
  }
}

}  // namespace

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

template <class T>
void tanh_inplace(T* p, int n) {
  constexpr int w = kW<T>;
  for (int i = 0; i < n; i += w) {
    T buf[w] = {};
    const int m = std::min(w, n - i);
    std::copy(p + i, p + i + m, buf);
    Vec<T> x = loadw(buf);
    tanh_n<T, 1>(&x);
    storew(buf, x);
    std::copy(buf, buf + m, p + i);
  }
}

namespace {
// the layers of n single-column networks; net g's weights are packed + g·packed_stride and its activations of
// layer l are at act(g, l). A layer narrower than a vector (the connector's output) with shared weights
// takes its tanh over all columns at once afterwards (tanh is elementwise: the same bits either way).
template <class T, class Act>
void forward_nets(const Layout& L, const T* packed, size_t packed_stride, int n, Act act, T* shared_y) {
  constexpr int kChunk = 8;
  for (int l = 0; l < L.n_layers(); ++l) {
    const PackedLayer p = packed_layer<T>(L, l);
    const bool narrow = p.out < kW<T> && shared_y && n > 1;
    for (int o0 = 0; o0 < p.out; o0 += kBlock<T>) {
      const int no = std::min(kBlock<T>, p.out - o0);
      const int nv = (no + kW<T> - 1) / kW<T>;
      for (int g0 = 0; g0 < n;) {
        const T* Wt[kChunk];
        const T* b[kChunk];
        const T* x[kChunk];
        T* y[kChunk];
        const int m = std::min(kChunk, n - g0);
        for (int g = 0; g < m; ++g) {
          const T* P = packed + (g0 + g) * packed_stride;
          Wt[g] = P + p.wt + o0;
          b[g] = P + p.b + o0;
          x[g] = act(g0 + g, l);
          y[g] = act(g0 + g, l + 1) + o0;
        }
        for (int g = 0; g < m;)
          g += narrow ? layer_forward_dispatch<T, false>(nv, m - g, Wt + g, p.outp, b + g, p.in, x + g, y + g, no)
                      : layer_forward_dispatch<T, true>(nv, m - g, Wt + g, p.outp, b + g, p.in, x + g, y + g, no);
        g0 += m;
      }
    }
    if (narrow) tanh_inplace(shared_y + static_cast<size_t>(L.activation_offset(l + 1)) * n, p.out * n);
  }
}
}  // namespace

template <class T>
void forward_packed(const Layout& L, const T* packed, int cols, T* acts) {
  forward_nets<T>(
      L, packed, 0, cols,
      [&](int c, int l) { return acts + static_cast<size_t>(L.activation_offset(l)) * cols + static_cast<size_t>(c) * L.sizes[l]; },
      acts);
}

template <class T>
void forward_packed_nets(const Layout& L, const T* packed, size_t packed_stride, int n, T* acts) {
  const size_t na = L.activation_count();
  forward_nets<T>(L, packed, packed_stride, n, [&](int g, int l) { return acts + g * na + L.activation_offset(l); },
                  nullptr);
}

void forward(const Layout& L, const double* params, int cols, double* acts) {
  std::vector<double> packed(packed_count(L));
  pack(L, params, packed.data());
  forward_packed(L, packed.data(), cols, acts);
}

template <class T>
void backward_packed(const Layout& L, const T* packed, int cols, const T* acts, const T* out_grad, T* param_grad,
                     T* in_grad, T* scratch) {
  constexpr int w = kW<T>;
  const int max_size = L.scratch_count() / 2;
  T* g_cur = scratch;                                          // gradient w.r.t. layer output
  T* g_prev = scratch + static_cast<size_t>(max_size) * cols;  // gradient w.r.t. layer input
  std::copy(out_grad, out_grad + static_cast<size_t>(L.out()) * cols, g_cur);
  for (int l = L.n_layers() - 1; l >= 0; --l) {
    const PackedLayer p = packed_layer<T>(L, l);
    const int in = p.in, out = p.out;
    const T* X = acts + static_cast<size_t>(L.activation_offset(l)) * cols;
    const T* Y = acts + static_cast<size_t>(L.activation_offset(l + 1)) * cols;
    // through tanh: dz = dy (1 − y²)
    for (int q = 0; q < out * cols; ++q) g_cur[q] *= (T(1.0) - Y[q] * Y[q]);
    // parameters: dW += dz xᵀ, db += dz, summed over the columns in order
    if (param_grad) {
      T* gW = param_grad + L.weight_offset(l);
      T* gb = param_grad + L.bias_offset(l);
      const int in4 = in / w * w;
      for (int o = 0; o < out; ++o) {
        T* row = gW + static_cast<size_t>(o) * in;
        for (int i0 = 0; i0 < in4; i0 += kBlock<T>) {
          const int nv = std::min(8, (in4 - i0) / w);
          DIVCOLL_NN_DISPATCH(T, nv, weight_grad_row, row + i0, X + i0, in, g_cur, out, cols, o)
        }
        // the inputs past the last whole vector, and the bias, in registers across the columns (in order);
        // through memory each column's update waited on the previous one's store
        const int nt = in - in4;
        T bias = gb[o];
#if defined(__AVX512F__)
        Vec<T> tail = load_masked<T>(row + in4, nt);
        for (int c = 0; c < cols; ++c) {
          const T go = g_cur[static_cast<size_t>(c) * out + o];
          tail = fmadd<T>(load_masked<T>(X + static_cast<size_t>(c) * in + in4, nt), go, tail);
          bias += go;
        }
        store_masked<T>(row + in4, nt, tail);
#else
        for (int c = 0; c < cols; ++c) {
          const T go = g_cur[static_cast<size_t>(c) * out + o];
          const T* x = X + static_cast<size_t>(c) * in;
          for (int i = in4; i < in; ++i) row[i] = std::fma(x[i], go, row[i]);
          bias += go;
        }
#endif
        gb[o] = bias;
      }
    }
    // input: dx = Wᵀ dz
    if (l == 0 && !in_grad) break;
    T* D = (l == 0) ? in_grad : g_prev;
    for (int c = 0; c < cols; ++c) {
      const T* g = g_cur + static_cast<size_t>(c) * out;
      T* d = D + static_cast<size_t>(c) * in;
      for (int i0 = 0; i0 < in; i0 += kBlock<T>) {
        const int n = std::min(kBlock<T>, in - i0);
        DIVCOLL_NN_DISPATCH(T, (n + w - 1) / w, layer_input_grad, packed + p.w + i0, p.inp, out, g, d + i0, n)
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
