#!/usr/bin/env bash
# Checks that the MLP's kernel-path objects (src/nn/mlp_<path>.cpp, each compiled for its own instruction set) define
# no global, weak or unique symbol outside their own namespace divcoll::nn::isa_<path>. Such a symbol (an inline
# function or template instance from a header, say) has one copy in the program, chosen by the linker among every
# object that defines it: the AVX-512 object's copy could then run on a CPU without AVX-512 and stop with SIGILL.
# Usage: check_kernel_symbols.sh OBJECT... ; exit 1 listing the symbols if there is one, else 0.
set -euo pipefail
[ $# -gt 0 ] || { echo "check_kernel_symbols: no object given" >&2; exit 2; }
bad=0
for obj in "$@"; do
  symbols=$(nm -C --defined-only "$obj") || { echo "check_kernel_symbols: nm cannot read $obj" >&2; exit 2; }
  while read -r type name; do
    case "$type" in
      [TWVuDRBGS]) ;;  # defined with external, weak or unique linkage
      *) continue ;;
    esac
    case "$name" in
      divcoll::nn::isa_*) ;;
      DW.ref.__gxx_personality_v0) ;;  # a pointer to the C++ runtime's unwinder, the same in every object
      *) echo "$(basename "$obj"): $type $name"; bad=1 ;;
    esac
  done < <(sed -E 's/^[0-9a-f]+ //' <<<"$symbols")
done
if [ "$bad" = 1 ]; then
  echo "kernel objects define symbols outside their path's namespace (above): keep kernel code inside DIVCOLL_NN_ISA" >&2
  exit 1
fi
echo "kernel objects: $# checked, every shared symbol inside its path's namespace"
