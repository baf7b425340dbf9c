#!/usr/bin/env bash
# README command 1: install what is missing, build, run the pipeline at the quick preset on every core,
# and draw its figures. Rerunning starts the quick run over.
set -euo pipefail
cd "$(dirname "$0")/.."
bash jobs/install-deps.sh
source jobs/mpi-env.sh
bash jobs/build.sh
mkdir -p out
mpirun -np "$(nproc)" build/divcoll run configs/quick.toml --out out/quick.h5 --force
build/divcoll report out/quick.h5 --out out/report
build/divcoll demo --out out/demo
echo
echo "run file: out/quick.h5    report: out/report/report.md (figures in out/report/figures/)    demo scenes: out/demo/"
