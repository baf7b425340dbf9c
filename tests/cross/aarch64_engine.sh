#!/usr/bin/env bash
# The engine on AArch64 under qemu-user, against the host: cross-compiles the engine (src/common, src/nn with its
# generic and neon kernel paths, src/sim) and tests/sim/engine_probe.cpp with Debian's aarch64-linux-gnu-g++ and the
# project's flags, warnings as errors; runs the parity scenes of shared/testdata/parity (300 steps with gradients)
# through it on both of its kernel paths, and through the host's engine_probe on every path the host CPU runs. Every
# digest of positions, velocities, contacts, travel and gradients must be the same.
# Usage: aarch64_engine.sh HOST_BUILD_DIR PARITY_DIR   (HOST_BUILD_DIR holds tests/engine_probe and generated/)
# Exit 0 all the same, 1 a digest differs or the cross build fails, 77 no cross compiler or qemu (ctest: skipped).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="$(cd "$1" && pwd)"
parity="$2"
if ! command -v aarch64-linux-gnu-g++ >/dev/null || ! command -v qemu-aarch64 >/dev/null; then
  echo "aarch64_engine: no aarch64-linux-gnu-g++ or qemu-aarch64 (Debian: g++-aarch64-linux-gnu qemu-user; bash jobs/install-deps.sh --test installs them)"
  exit 77
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
sources=("$root"/src/common/*.cpp "$root"/src/sim/*.cpp "$root"/src/nn/mlp.cpp "$root"/src/nn/kernel_path.cpp
         "$root"/src/nn/mlp_generic.cpp "$root"/src/nn/mlp_neon.cpp "$build"/generated/git_commit.cpp
         "$root"/tests/sim/engine_probe.cpp)
start=$(date +%s)
# the flags of CMakeLists.txt's engine (Release: -O3 -DNDEBUG), as many files at a time as there are cores, linked
# statically so that qemu needs no AArch64 libraries beside it
flags=(-std=c++20 -O3 -DNDEBUG -Wall -Wextra -Werror -ffp-contract=off -fno-math-errno -DDIVCOLL_VERSION=\"cross\"
       "-DDIVCOLL_SOURCE_DIR=\"$root\"" "-I$root/src" "-I$root/tests")
pids=()
failed=0
for i in "${!sources[@]}"; do
  aarch64-linux-gnu-g++ "${flags[@]}" -c "${sources[$i]}" -o "$tmp/$i.o" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$(nproc)" ]; then wait "${pids[0]}" || failed=1; pids=("${pids[@]:1}"); fi
done
for p in "${pids[@]}"; do wait "$p" || failed=1; done
[ "$failed" = 0 ] || { echo "aarch64_engine: the cross build failed (above)" >&2; exit 1; }
aarch64-linux-gnu-g++ -static -o "$tmp/engine_probe" "$tmp"/*.o
echo "aarch64_engine: cross build with -Werror in $(( $(date +%s) - start )) s"

"$build/tests/engine_probe" --write-scenes "$tmp" "$parity"/scene*.h5
scenes=("$tmp"/scene*.bin)
run() {  # label, then the command; its digests (without the kernels line) into $tmp/label
  local label="$1"; shift
  "$@" "${scenes[@]}" > "$tmp/$label.out"
  grep -v '^kernels ' "$tmp/$label.out" > "$tmp/$label"
  echo "$label: $(grep '^kernels ' "$tmp/$label.out")"
}
run host-generic env DIVCOLL_KERNELS=generic "$build/tests/engine_probe"
run host-best env DIVCOLL_KERNELS=auto "$build/tests/engine_probe"
run aarch64-generic env DIVCOLL_KERNELS=generic qemu-aarch64 "$tmp/engine_probe"
run aarch64-neon env DIVCOLL_KERNELS=neon qemu-aarch64 "$tmp/engine_probe"
cat "$tmp/host-generic"
status=0
for l in host-best aarch64-generic aarch64-neon; do
  if ! diff -u "$tmp/host-generic" "$tmp/$l"; then
    echo "aarch64_engine: $l differs from host-generic" >&2
    status=1
  fi
done
[ "$status" = 0 ] && echo "aarch64_engine: ${#scenes[@]} parity scenes, the same digests on the host's paths and on AArch64's generic and neon"
exit "$status"
