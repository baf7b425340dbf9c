#!/usr/bin/env bash
# The unit tests under AddressSanitizer and UndefinedBehaviorSanitizer (the last step of jobs/test.sh).
# Usage: jobs/sanitize.sh [gtest filter]
#
# Builds the single-process test binary (tests/*/…_test.cpp, not the multi-process suite of tests/mpi) into
# ./build-sanitize with -fsanitize=address,undefined at -O1 and runs it: any heap or stack overflow, use after
# free, leak or undefined behaviour (signed overflow, misaligned or null access, out-of-range shift, ...) stops the
# run with the sanitizer's report and a non-zero exit. The build is portable (-DDIVCOLL_NATIVE=OFF: GCC 12's
# AVX-512 headers raise false uninitialised-value warnings at -O1) and does not treat warnings as errors (the
# Release build of jobs/build.sh does). Tests that start the divcoll binary or mpirun (the tiny preset's golden
# digest, the CLI's and grad-diag's end-to-end runs) are left out: they are the multi-process suite's. So is the CMA-ES test: in this
# build Eigen's blocks made in src/evo/es_cmaes.cpp are freed inside Debian's uninstrumented libpagmo, which
# AddressSanitizer reports as a bad free (a mismatch of the instrumented build with the library, not of the code).
set -euo pipefail
cd "$(dirname "$0")/.."
source jobs/mpi-env.sh
filter="${1:-}"
if [[ -z "$filter" ]]; then
  filter="-*TinyGolden.*:KernelPathChoice.*:Cli.*:GradDiag.*:ConnectorOpt.Cmaes*"
fi
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
      -DDIVCOLL_SANITIZE=ON -DDIVCOLL_NATIVE=OFF -DDIVCOLL_WERROR=OFF >/dev/null
cmake --build build-sanitize -j"$(nproc)" --target divcoll_tests
export ASAN_OPTIONS="abort_on_error=0:halt_on_error=1:detect_leaks=1:strict_string_checks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export GTEST_COLOR=no
start=$(date +%s)
build-sanitize/tests/divcoll_tests --gtest_filter="$filter" --gtest_brief=1
echo "sanitize: the unit tests passed under AddressSanitizer and UBSan in $(( $(date +%s) - start )) s"
