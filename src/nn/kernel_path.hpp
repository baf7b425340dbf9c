// which copy of the MLP kernels runs (nn/mlp_kernels.inc). One binary holds a copy per instruction set of its
// architecture (x86-64: generic, avx2, avx512; AArch64: generic, neon) and runs the best one the CPU has, or the one
// the environment variable DIVCOLL_KERNELS names (generic, avx2, avx512, neon, or auto for the best). Every path
// gives the same bits; the choice changes only the speed. The rest of the program is compiled once, for the build's
// instruction set (x86-64's baseline unless DIVCOLL_NATIVE), and its results do not depend on it either.
#pragma once

#include <string>
#include <vector>

namespace divcoll::nn {

enum class KernelPath { generic, avx2, avx512, neon };

const char* kernel_path_name(KernelPath p);
// "generic" → KernelPath::generic, and so on; throws std::runtime_error naming the choices on anything else
KernelPath parse_kernel_path(const std::string& name);
// the paths this binary holds, generic first
std::vector<KernelPath> built_kernel_paths();
// whether this binary holds p and this CPU can run it
bool can_run(KernelPath p);
// the fastest path that can run here
KernelPath best_kernel_path();
// the path in use: chosen at the first call, DIVCOLL_KERNELS if it is set (std::runtime_error, saying why and what
// can run, if that path is unknown, not built or not runnable on this CPU), else best_kernel_path()
KernelPath kernel_path();
// use p from now on (tests, `divcoll bench --kernels`); throws as kernel_path() does if p cannot run here
void set_kernel_path(KernelPath p);

// the CPU's model name as the operating system gives it (/proc/cpuinfo), and its architecture, e.g.
// "AMD EPYC 7B13 (x86_64)"; "unknown (x86_64)" where the name cannot be read
std::string cpu_description();

}  // namespace divcoll::nn
