#!/usr/bin/env bash
# Configures and builds divcoll (Release, warnings as errors) into ./build. Usage: jobs/build.sh [extra cmake args]
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DDIVCOLL_WERROR=ON "$@" >/dev/null
cmake --build build -j"$(nproc)"
