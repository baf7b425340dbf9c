#!/usr/bin/env bash
# README command 1: install what is missing, build, run the demo pipeline.
set -euo pipefail
cd "$(dirname "$0")/.."
bash jobs/install-deps.sh
source jobs/mpi-env.sh
bash jobs/build.sh
mkdir -p out/demo
./build/divcoll demo --out out/demo
