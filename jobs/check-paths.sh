#!/usr/bin/env bash
# The builds beside the default one, each with warnings as errors, so that an instruction-set path that stops
# compiling, or stops giving the committed results, fails README command 2 (and CI) on any machine:
#   build-native  -march=native: the whole program for this CPU; its tiny run must give the golden digest
#                 (tests/mpi/tiny_golden.txt);
#   build-v4      on x86-64, -march=x86-64-v4: the whole program for AVX-512 CPUs, compiled; its tiny run is
#                 checked too where this CPU has AVX-512.
# The default build (jobs/build.sh) already compiles every kernel path of its architecture (generic, avx2 and avx512
# on x86-64), ctest runs the golden digest on each path this CPU has, and cross.aarch64_engine runs AArch64's engine
# under qemu-user against this one. Usage: bash jobs/check-paths.sh (after jobs/build.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
source jobs/mpi-env.sh
golden=$(grep -v '^#' tests/mpi/tiny_golden.txt | head -1 | cut -d' ' -f1)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

runs_here() {  # whether this CPU runs code built with -march=$1
  case "$1" in
    native) return 0 ;;
    x86-64-v4) for f in avx512f avx512bw avx512cd avx512dq avx512vl; do grep -qw "$f" /proc/cpuinfo || return 1; done ;;
    *) return 1 ;;
  esac
}

check() {  # build dir, -march value
  local dir="$1" march="$2" start
  start=$(date +%s)
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DDIVCOLL_WERROR=ON -DDIVCOLL_TESTS=OFF -DDIVCOLL_MARCH="$march" >/dev/null
  cmake --build "$dir" -j"$(nproc)" --target divcoll >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
  echo "check-paths: -march=$march builds with -Werror ($(( $(date +%s) - start )) s)"
  if runs_here "$march"; then
    "$dir/divcoll" --version >"$tmp/version"
    "$dir/divcoll" run configs/tiny.toml --out "$tmp/tiny.h5" run.progress_every_s=0 >"$tmp/run.log" 2>&1 \
      || { cat "$tmp/run.log"; exit 1; }
    local digest
    digest=$("$dir/divcoll" compare --digest "$tmp/tiny.h5")
    rm -f "$tmp/tiny.h5"
    if [ "$digest" != "$golden" ]; then
      echo "check-paths: -march=$march gives the tiny digest $digest, not the committed $golden" >&2
      exit 1
    fi
    echo "check-paths: -march=$march, $(grep '^kernels' "$tmp/version"): the tiny run gives the committed digest $golden"
  else
    echo "check-paths: -march=$march does not run on this CPU ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')): compiled only"
  fi
}

check build-native native
if [ "$(uname -m)" = x86_64 ]; then
  check build-v4 x86-64-v4
fi
