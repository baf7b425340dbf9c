// the MLP kernels for any CPU: GCC vector extensions lowered to the instruction set the file is compiled for (SSE2
// on x86-64's baseline), a fused multiply-add per lane through std::fma; the path of last resort, and the reference
// the others are tested against
#define DIVCOLL_NN_ISA isa_generic
#include "nn/mlp_kernels.inc"
