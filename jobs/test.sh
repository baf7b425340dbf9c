#!/usr/bin/env bash
# README command 2: install what is missing, build, run every test, build the other instruction-set paths with
# warnings as errors and check their results (jobs/check-paths.sh), then the unit tests again under AddressSanitizer
# and UBSan (jobs/sanitize.sh; DIVCOLL_SKIP_SANITIZE=1 leaves that leg out).
set -euo pipefail
cd "$(dirname "$0")/.."
bash jobs/install-deps.sh --test
source jobs/mpi-env.sh
bash jobs/build.sh
(cd build && ctest --output-on-failure -j2 --timeout 900)
bash jobs/check-paths.sh
if [[ "${DIVCOLL_SKIP_SANITIZE:-0}" != 1 ]]; then
  bash jobs/sanitize.sh
fi
