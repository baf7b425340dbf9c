#include "nn/kernel_path.hpp"

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace divcoll::nn {

namespace {
constexpr int kUnset = -1;
std::atomic<int> g_path{kUnset};

std::string names_of(const std::vector<KernelPath>& ps) {
  std::string s;
  for (KernelPath p : ps) s += (s.empty() ? "" : ", ") + std::string(kernel_path_name(p));
  return s;
}

std::vector<KernelPath> runnable() {
  std::vector<KernelPath> r;
  for (KernelPath p : built_kernel_paths())
    if (can_run(p)) r.push_back(p);
  return r;
}

void check_runs(KernelPath p) {
  if (can_run(p)) return;
  bool built = false;
  for (KernelPath b : built_kernel_paths()) built = built || b == p;
  throw std::runtime_error(std::string("kernel path ") + kernel_path_name(p) +
                           (built ? " cannot run on this CPU (" + cpu_description() + ")"
                                  : std::string(" is not built into this binary (its architecture has other paths)")) +
                           "; paths that run here: " + names_of(runnable()));
}
}  // namespace

const char* kernel_path_name(KernelPath p) {
  switch (p) {
    case KernelPath::generic: return "generic";
    case KernelPath::avx2: return "avx2";
    case KernelPath::avx512: return "avx512";
    case KernelPath::neon: return "neon";
  }
  return "?";
}

KernelPath parse_kernel_path(const std::string& name) {
  for (KernelPath p : {KernelPath::generic, KernelPath::avx2, KernelPath::avx512, KernelPath::neon})
    if (name == kernel_path_name(p)) return p;
  throw std::runtime_error("unknown kernel path '" + name + "' (choose generic, avx2, avx512, neon or auto)");
}

std::vector<KernelPath> built_kernel_paths() {
#if defined(__x86_64__)
  return {KernelPath::generic, KernelPath::avx2, KernelPath::avx512};
#elif defined(__aarch64__)
  return {KernelPath::generic, KernelPath::neon};
#else
  return {KernelPath::generic};
#endif
}

bool can_run(KernelPath p) {
  switch (p) {
    case KernelPath::generic: return true;
#if defined(__x86_64__)
    // the levels the kernels' files are compiled for (-march=x86-64-v3, -march=x86-64-v4): all of each level's
    // instructions, not only the ones the kernels ask for by name, since the compiler may use any of them
    case KernelPath::avx2: return __builtin_cpu_supports("x86-64-v3");
    case KernelPath::avx512: return __builtin_cpu_supports("x86-64-v4");
#elif defined(__aarch64__)
    case KernelPath::neon: return true;  // Advanced SIMD is part of every AArch64 CPU
#endif
    default: return false;
  }
}

KernelPath best_kernel_path() {
  KernelPath best = KernelPath::generic;
  for (KernelPath p : built_kernel_paths())
    if (can_run(p)) best = p;  // built_kernel_paths lists slower paths first
  return best;
}

KernelPath kernel_path() {
  const int cur = g_path.load(std::memory_order_acquire);
  if (cur != kUnset) return static_cast<KernelPath>(cur);
  KernelPath p = best_kernel_path();
  if (const char* env = std::getenv("DIVCOLL_KERNELS"); env && *env && std::string(env) != "auto") {
    try {
      p = parse_kernel_path(env);
      check_runs(p);
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string("DIVCOLL_KERNELS=") + env + ": " + e.what());
    }
  }
  int expected = kUnset;
  g_path.compare_exchange_strong(expected, static_cast<int>(p), std::memory_order_acq_rel);
  return static_cast<KernelPath>(g_path.load(std::memory_order_acquire));
}

void set_kernel_path(KernelPath p) {
  check_runs(p);
  g_path.store(static_cast<int>(p), std::memory_order_release);
}

std::string cpu_description() {
#if defined(__x86_64__)
  const std::string arch = "x86_64";
#elif defined(__aarch64__)
  const std::string arch = "aarch64";
#else
  const std::string arch = "other";
#endif
  std::ifstream in("/proc/cpuinfo");
  std::string line, implementer, part;
  auto value = [](const std::string& l) {
    const size_t c = l.find(':');
    size_t b = c == std::string::npos ? l.size() : l.find_first_not_of(" \t", c + 1);
    return b == std::string::npos ? std::string() : l.substr(b);
  };
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) return value(line) + " (" + arch + ")";
    if (line.rfind("CPU implementer", 0) == 0 && implementer.empty()) implementer = value(line);
    if (line.rfind("CPU part", 0) == 0 && part.empty()) part = value(line);
  }
  if (!implementer.empty()) return "implementer " + implementer + " part " + part + " (" + arch + ")";
  return "unknown (" + arch + ")";
}

}  // namespace divcoll::nn
