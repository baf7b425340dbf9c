#!/usr/bin/env bash
# Scaling benchmark (prints; it is not a test): wall time per stage of one preset at 1, 2, 3, 4 ranks,
# each rank's busy share, and the load imbalance, from the run files' attributes. The machine's load
# average is printed before and after each run: on a shared machine the wall times suffer, and the ratio of
# two runs' wall times mostly shows how the load changed between them; 2 × busy(2 ranks) / busy(1 rank) is
# the speed-up the busy shares imply with two cores to itself (on a quiet machine it came out 0.03-0.08
# above the measured ratio). Ranks beyond the
# machine's cores are oversubscribed (said so in the table). Writes OUT/scaling.csv, OUT/scaling.md and
# OUT/scaling.png (divcoll_post.figures.fig_scaling).
# The entry "1+1" in RANKS runs two independent 1-rank runs of the same config at once (no MPI between them:
# OUT/concurrent_a.h5, OUT/concurrent_b.h5). Twice one rank's time over their mean time is what this machine
# gives two processes side by side (shared caches, memory bandwidth, the host's scheduling): the table
# prints it as the cap for 2 ranks, which no farm can beat, beside the 2-rank ratio.
#   bash jobs/bench-scaling.sh [CONFIG=configs/quick.toml] [OUT=out/scaling] [RANKS="1 2 3 4"]
#   e.g. bash jobs/bench-scaling.sh configs/quick.toml out/cap "1 1+1 2"
set -euo pipefail
cd "$(dirname "$0")/.."
CONFIG=${1:-configs/quick.toml}
OUT=${2:-out/scaling}
RANKS=${3:-1 2 3 4}
source jobs/mpi-env.sh
[ -x build/divcoll ] || bash jobs/build.sh
mkdir -p "$OUT"
cores=$(nproc)
for n in $RANKS; do
  if [ "$n" = "1+1" ]; then
    echo "== two 1-rank runs at once; load average $(cut -d' ' -f1-3 /proc/loadavg)"
    t0=$(date +%s.%N)
    pids=()
    # each on a core of its own, as mpirun binds the ranks of one 2-rank run (two plain `mpirun -np 1` would
    # both bind to core 0 and share it)
    core=0
    for side in a b; do
      taskset -c "$core" mpirun --bind-to none -np 1 build/divcoll run "$CONFIG" run.progress_every_s=0 \
        --out "$OUT/concurrent_$side.h5" --force > "$OUT/concurrent_$side.log" 2>&1 &
      core=$(( (core + 1) % cores ))
      pids+=($!)
    done
    for p in "${pids[@]}"; do wait "$p" || { echo "bench-scaling: a concurrent run failed (see $OUT/concurrent_*.log)" >&2; exit 1; }; done
    grep -hE "^stage" "$OUT/concurrent_a.log" || true
    echo "total $(echo "$(date +%s.%N) - $t0" | bc -l | cut -c1-6) s; load average after $(cut -d' ' -f1-3 /proc/loadavg)"
    continue
  fi
  echo "== $n rank(s); load average $(cut -d' ' -f1-3 /proc/loadavg)"
  t0=$(date +%s.%N)
  mpirun -np "$n" build/divcoll run "$CONFIG" run.progress_every_s=0 --out "$OUT/run_np$n.h5" --force \
    | grep -E "^stage" || true
  echo "total $(echo "$(date +%s.%N) - $t0" | bc -l | cut -c1-6) s; load average after $(cut -d' ' -f1-3 /proc/loadavg)"
done
PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.figures.fig_scaling "$OUT" --cores "$cores"
