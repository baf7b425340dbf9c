#!/usr/bin/env bash
# README command 1: install what is missing (build and runtime packages only), build, run the pipeline at the
# quick preset on every core, write its report (report.md, report.html, figures, the movie of a uniform and a
# diverse pair) and the demo. The Supplementary Movie is one command more (it doubles the report's time):
#   build/divcoll report out/quick.h5 --out out/report --movie
# One line per step; the long outputs go to out/logs/. Rerunning starts the quick run over.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p out/logs
t0=$(date +%s)
say() { printf '[%4ds] %s\n' "$(( $(date +%s) - t0 ))" "$*"; }
fail() { say "FAILED: $1 (see $2)"; tail -n 5 "$2" | cut -c1-116 >&2; exit 1; }

say "install: Debian packages for building and running (apt's output: out/logs/apt.log)"
bash jobs/install-deps.sh --only build --log out/logs/apt.log | cut -c1-116 || fail "install" out/logs/apt.log
# what only the report needs (Python's numpy, matplotlib ..., ffmpeg) installs while the program builds and runs
bash jobs/install-deps.sh --only report --log out/logs/apt-report.log >out/logs/apt-report.out 2>&1 &
apt_pid=$!
source jobs/mpi-env.sh
say "build: cmake, $(nproc) jobs (output: out/logs/build.log)"
bash jobs/build.sh --target divcoll >out/logs/build.log 2>&1 || fail "build" out/logs/build.log

# the seven stages of the run, one line each. Their share of the quick run's time (2 ranks, measured
# 2026-12-01: agents 5, connectors 42, deploy 31, specialists 22, scaling 9, graded 36, analysis 25 s) gives
# the ETA: elapsed x (what is left / what is done).
say "run: configs/quick.toml on $(nproc) ranks, 7 stages (output: out/logs/run.log)"
declare -A cost=([agents]=5 [connectors]=42 [deploy]=31 [specialists]=22 [scaling]=9 [graded]=36 [analysis]=25)
total=170 done_cost=0 k=0 r0=$(date +%s)
set +e
mpirun -np "$(nproc)" build/divcoll run configs/quick.toml --out out/quick.h5 --force 2>&1 | tee out/logs/run.log |
  while IFS= read -r line; do
    if [[ $line =~ ^stage\ ([a-z]+):\ done\ in\ ([0-9.]+)\ s ]]; then
      st=${BASH_REMATCH[1]} secs=${BASH_REMATCH[2]}
      k=$((k + 1)) done_cost=$((done_cost + ${cost[$st]:-0}))
      el=$(( $(date +%s) - r0 ))
      eta=$(( done_cost > 0 ? el * (total - done_cost) / done_cost : 0 ))
      say "stage $k/7 $st done in ${secs%.*} s; run ETA $((eta / 60)) min $((eta % 60)) s"
    fi
  done
rc=${PIPESTATUS[0]}
set -e
[ "$rc" -eq 0 ] || fail "run (exit $rc)" out/logs/run.log

wait "$apt_pid" || fail "install of the report's packages" out/logs/apt-report.out
cut -c1-116 out/logs/apt-report.out

# the demo runs beside the report (each mostly one core; the report's movie clips share the cores too)
say "report: out/report/report.html and report.md, figures, a movie (output: out/logs/report.log)"
build/divcoll demo --run out/quick.h5 --out out/demo --movie >out/logs/demo.log 2>&1 &
demo_pid=$!
build/divcoll report out/quick.h5 --out out/report >out/logs/report.log 2>&1 || fail "report" out/logs/report.log
grep -E "^(divcoll: Python|report: wrote)" out/logs/report.log | cut -c1-116
say "demo: the run's trained agents and connector, walking (out/demo/demo.mp4)"
wait "$demo_pid" || fail "demo" out/logs/demo.log
grep -A2 '^environment' out/logs/demo.log | cut -c1-116
say "done. Open out/report/report.html in a browser; the run file is out/quick.h5."
say "the Supplementary Movie (1-2 min more): build/divcoll report out/quick.h5 --out out/report --movie"
