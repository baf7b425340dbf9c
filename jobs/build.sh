#!/usr/bin/env bash
# Configures and builds divcoll (Release, warnings as errors) into ./build.
# Usage: jobs/build.sh [--target NAME] [extra cmake args]
#   --target NAME  builds that target only (README command 1 builds `divcoll`, the program, and none of the
#                  tests); without it every target, the test binaries included (README command 2).
set -euo pipefail
cd "$(dirname "$0")/.."
target=()
if [ "${1:-}" = --target ]; then
  target=(--target "$2")
  shift 2
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DDIVCOLL_WERROR=ON "$@" >/dev/null
cmake --build build -j"$(nproc)" "${target[@]}"
