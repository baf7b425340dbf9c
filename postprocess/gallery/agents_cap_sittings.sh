#!/bin/bash
# The quick preset's agents stage alone, alternating: 1 rank, two independent 1-rank runs at once (one per core:
# the machine's cap for 2 ranks is 2 × t(1 rank) / t(1+1)), and 2 ranks. Prints each run's wall time and its
# computing threads' CPU seconds (the stage's attributes). A benchmark that prints, not a test.
#   bash postprocess/gallery/agents_cap_sittings.sh [SITTINGS=5] [OUT=/tmp/agents_cap]
set -euo pipefail
cd "$(dirname "$0")/../.."
N=${1:-5}
OUT=${2:-/tmp/agents_cap}
mkdir -p "$OUT"
source jobs/mpi-env.sh
[ -x build/divcoll ] || bash jobs/build.sh
w() {
  /usr/bin/python3 -c "import h5py,sys; a=h5py.File(sys.argv[1],'r')['agents'].attrs; print('%.4f s, computing CPU %s s' % (a['wall_s_last_session'], a['compute_cpu_s_per_rank_last_session']))" "$1"
}
for k in $(seq 1 "$N"); do
  mpirun -np 1 build/divcoll run configs/quick.toml run.progress_every_s=0 --out "$OUT/one.h5" --force 'run.stages=["agents"]' > /dev/null 2>&1
  echo "$k 1 rank: $(w "$OUT/one.h5")"
  taskset -c 0 mpirun --bind-to none -np 1 build/divcoll run configs/quick.toml run.progress_every_s=0 --out "$OUT/a.h5" --force 'run.stages=["agents"]' > /dev/null 2>&1 &
  taskset -c 1 mpirun --bind-to none -np 1 build/divcoll run configs/quick.toml run.progress_every_s=0 --out "$OUT/b.h5" --force 'run.stages=["agents"]' > /dev/null 2>&1 &
  wait
  echo "$k 1+1 a: $(w "$OUT/a.h5")"
  echo "$k 1+1 b: $(w "$OUT/b.h5")"
  mpirun -np 2 build/divcoll run configs/quick.toml run.progress_every_s=0 --out "$OUT/two.h5" --force 'run.stages=["agents"]' > /dev/null 2>&1
  echo "$k 2 ranks: $(w "$OUT/two.h5")"
done
