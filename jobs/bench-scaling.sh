#!/usr/bin/env bash
# Scaling benchmark (prints; it is not a test): wall time per stage of one preset at 1, 2, 3, 4 ranks,
# each rank's busy share, and the load imbalance, from the run files' attributes. The machine's load
# average is printed before and after each run: on a shared machine the wall times suffer, and the ratio of
# two runs' wall times mostly shows how the load changed between them; 2 × busy(2 ranks) / busy(1 rank) is
# the speed-up the busy shares imply with two cores to itself (on a quiet machine it came out 0.03-0.08
# above the measured ratio). Ranks beyond the
# machine's cores are oversubscribed (said so in the table). Writes OUT/scaling.csv, OUT/scaling.md and
# OUT/scaling.png (postprocess/fig_scaling.py).
#   bash jobs/bench-scaling.sh [CONFIG=configs/quick.toml] [OUT=out/scaling] [RANKS="1 2 3 4"]
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
  echo "== $n rank(s); load average $(cut -d' ' -f1-3 /proc/loadavg)"
  t0=$(date +%s.%N)
  mpirun -np "$n" build/divcoll run "$CONFIG" run.progress_every_s=0 --out "$OUT/run_np$n.h5" --force \
    | grep -E "^stage" || true
  echo "total $(echo "$(date +%s.%N) - $t0" | bc -l | cut -c1-6) s; load average after $(cut -d' ' -f1-3 /proc/loadavg)"
done
/usr/bin/python3 postprocess/fig_scaling.py "$OUT" --cores "$cores"
