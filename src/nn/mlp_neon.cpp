// the MLP kernels for 64-bit ARM (AArch64's Advanced SIMD, which every AArch64 CPU has: Graviton, Ampere, Apple
// silicon under Linux); fused multiply-adds by FMLA on two 128-bit registers per vector
#if !defined(__aarch64__)
#error "mlp_neon.cpp is for AArch64 only (CMakeLists.txt)"
#endif
#define DIVCOLL_NN_ISA isa_neon
#include "nn/mlp_kernels.inc"
