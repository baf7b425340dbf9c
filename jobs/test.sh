#!/usr/bin/env bash
# README command 2: install what is missing, build, run every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash jobs/install-deps.sh --test
source jobs/mpi-env.sh
bash jobs/build.sh
cd build
ctest --output-on-failure -j2 --timeout 900
