// the MLP's kernel paths (nn/kernel_path.hpp): every path this CPU can run gives the generic path's bits, forward,
// backward and tanh, double and float, on the three layouts and on column counts that leave partial vectors; a path
// the CPU cannot run is refused with a message, and so is an unknown name
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "common/rng.hpp"
#include "nn/kernel_path.hpp"
#include "nn/mlp.hpp"

namespace divcoll {
namespace {

// everything the kernels compute for one layout, column count and seed, as bytes
template <class T>
std::vector<unsigned char> kernel_outputs(const nn::Layout& L, int cols, uint64_t seed) {
  Rng rng = make_rng(seed, 1, cols);
  std::vector<double> params(L.param_count());
  for (double& p : params) p = 0.4 * normal(rng);
  std::vector<T> packed(nn::packed_count<T>(L));
  nn::pack<T>(L, params.data(), packed.data());
  const size_t na = L.activation_count();
  std::vector<T> acts(na * cols);
  for (size_t q = 0; q < static_cast<size_t>(L.in()) * cols; ++q) acts[q] = static_cast<T>(1.5 * normal(rng));
  nn::forward_packed<T>(L, packed.data(), cols, acts.data());
  std::vector<T> out_grad(static_cast<size_t>(L.out()) * cols);
  for (T& g : out_grad) g = static_cast<T>(normal(rng));
  std::vector<T> pgrad(L.param_count(), T(0)), in_grad(static_cast<size_t>(L.in()) * cols);
  std::vector<T> scratch(static_cast<size_t>(L.scratch_count()) * cols);
  nn::backward_packed<T>(L, packed.data(), cols, acts.data(), out_grad.data(), pgrad.data(), in_grad.data(),
                         scratch.data());
  // n networks with their own weights, one column each
  std::vector<T> many(packed.size() * cols);
  for (int g = 0; g < cols; ++g)
    for (size_t q = 0; q < packed.size(); ++q) many[g * packed.size() + q] = packed[q] * static_cast<T>(1 + 0.1 * g);
  std::vector<T> nets(na * cols);
  for (int g = 0; g < cols; ++g)
    for (int q = 0; q < L.in(); ++q) nets[g * na + q] = static_cast<T>(normal(rng));
  nn::forward_packed_nets<T>(L, many.data(), packed.size(), cols, nets.data());
  std::vector<T> th(37);
  for (size_t q = 0; q < th.size(); ++q) th[q] = static_cast<T>(-9.0 + 0.5 * q);
  nn::tanh_inplace<T>(th.data(), static_cast<int>(th.size()));

  std::vector<unsigned char> bytes;
  for (const std::vector<T>* v : {&acts, &pgrad, &in_grad, &nets, &th}) {
    const auto* b = reinterpret_cast<const unsigned char*>(v->data());
    bytes.insert(bytes.end(), b, b + v->size() * sizeof(T));
  }
  return bytes;
}

template <class T>
std::vector<std::vector<unsigned char>> all_outputs() {
  std::vector<std::vector<unsigned char>> out;
  for (const nn::Layout& L : {nn::agent_layout(54), nn::connector_layout(), nn::joint_connector_layout()})
    for (int cols : {1, 2, 3, 5, 10, 17}) out.push_back(kernel_outputs<T>(L, cols, 100 + cols));
  return out;
}

class KernelPaths : public ::testing::Test {
 protected:
  void TearDown() override { nn::set_kernel_path(nn::best_kernel_path()); }
};

TEST_F(KernelPaths, EveryPathThisCpuRunsGivesTheGenericBits) {
  nn::set_kernel_path(nn::KernelPath::generic);
  const auto want_d = all_outputs<double>();
  const auto want_f = all_outputs<float>();
  int compared = 0;
  for (nn::KernelPath p : nn::built_kernel_paths()) {
    if (p == nn::KernelPath::generic || !nn::can_run(p)) continue;
    nn::set_kernel_path(p);
    EXPECT_TRUE(all_outputs<double>() == want_d) << nn::kernel_path_name(p) << " differs from generic in double";
    EXPECT_TRUE(all_outputs<float>() == want_f) << nn::kernel_path_name(p) << " differs from generic in float";
    ++compared;
  }
  std::printf("kernel paths compared with generic on %s: %d\n", nn::cpu_description().c_str(), compared);
}

TEST_F(KernelPaths, BestPathRunsAndIsBuilt) {
  const nn::KernelPath best = nn::best_kernel_path();
  EXPECT_TRUE(nn::can_run(best));
  EXPECT_TRUE(nn::can_run(nn::KernelPath::generic));
  bool built = false;
  for (nn::KernelPath p : nn::built_kernel_paths()) built = built || p == best;
  EXPECT_TRUE(built);
#if defined(__x86_64__)
  EXPECT_EQ(nn::can_run(nn::KernelPath::avx2), static_cast<bool>(__builtin_cpu_supports("x86-64-v3")));
  EXPECT_FALSE(nn::can_run(nn::KernelPath::neon));
#endif
}

TEST_F(KernelPaths, PathsThatCannotRunHereAreRefusedWithAReason) {
  for (nn::KernelPath p : {nn::KernelPath::generic, nn::KernelPath::avx2, nn::KernelPath::avx512,
                           nn::KernelPath::neon}) {
    if (nn::can_run(p)) continue;
    try {
      nn::set_kernel_path(p);
      ADD_FAILURE() << nn::kernel_path_name(p) << " was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(nn::kernel_path_name(p)), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("paths that run here: generic"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(nn::parse_kernel_path("sse9"), std::runtime_error);
  EXPECT_EQ(nn::parse_kernel_path("avx2"), nn::KernelPath::avx2);
}

}  // namespace
}  // namespace divcoll
