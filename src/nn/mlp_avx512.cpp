// the MLP kernels for x86-64-v4 (AVX-512 F, BW, CD, DQ, VL: Intel Skylake-SP and later, AMD Zen 4); compiled with
// -march=x86-64-v4 (CMakeLists.txt) and run only on a CPU that has it (nn/kernel_path.cpp)
#if !defined(__AVX512F__)
#error "mlp_avx512.cpp must be compiled with -march=x86-64-v4 (CMakeLists.txt)"
#endif
#define DIVCOLL_NN_ISA isa_avx512
#include "nn/mlp_kernels.inc"
