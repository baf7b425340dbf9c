// the MLP kernels for x86-64-v3 (AVX2 with FMA: Intel Haswell and later, AMD Zen); compiled with -march=x86-64-v3
// (CMakeLists.txt) and run only on a CPU that has it (nn/kernel_path.cpp)
#if !defined(__AVX2__) || !defined(__FMA__)
#error "mlp_avx2.cpp must be compiled with -march=x86-64-v3 (CMakeLists.txt)"
#endif
#define DIVCOLL_NN_ISA isa_avx2
#include "nn/mlp_kernels.inc"
