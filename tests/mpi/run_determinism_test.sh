#!/usr/bin/env bash
# SPEC §10 end to end: the same config and seed give bit-identical run-file datasets with 1, 2 and 3
# ranks (3 oversubscribed on 2 cores), and after the whole job (trials 1, 2) or one rank of it (trial 3)
# is killed (SIGKILL) at a random point and resumed, with another rank count. Usage: run_determinism_test.sh DIVCOLL SOURCE_DIR CMD CONFIG [overrides]
# (CMD: evolve, or run for every implemented stage)
set -euo pipefail
D=$1 SRC=$2 CMD=$3 CFG=$4
shift 4
OVR=("$@")
source "$SRC/jobs/mpi-env.sh"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT

echo "== uninterrupted with 1, 2, 3 ranks"
"$D" "$CMD" "$CFG" "${OVR[@]}" --out "$W/r1.h5" > "$W/r1.log"
t0=$(date +%s.%N)
mpirun -np 2 "$D" "$CMD" "$CFG" "${OVR[@]}" --out "$W/r2.h5" > "$W/r2.log"
T=$(echo "$(date +%s.%N) - $t0" | bc -l)
mpirun -np 3 "$D" "$CMD" "$CFG" "${OVR[@]}" --out "$W/r3.h5" > "$W/r3.log"
"$D" compare "$W/r1.h5" "$W/r2.h5"
"$D" compare "$W/r1.h5" "$W/r3.h5"

echo "== killed and resumed"
for trial in 1 2 3; do
  rm -f "$W/k.h5" "$W/k.h5.ckpt"
  # start with 2 ranks; the output path is unique, so it names every process of the job
  mpirun -np 2 "$D" "$CMD" "$CFG" "${OVR[@]}" run.progress_every_s=0 --out "$W/k.h5" > "$W/k.log" 2>&1 &
  job=$!
  # kill at a random moment between 30% and 80% of the uninterrupted 2-rank run's wall time: every
  # process of the job at once (mpirun and the ranks, which Open MPI puts in process groups of their own)
  sleep "$(echo "$T * (0.3 + 0.5 * $RANDOM / 32767)" | bc -l)"
  if [ "$trial" = 3 ]; then
    # one rank only (not mpirun): Open MPI must notice and end the others
    victim=$(pgrep -f -- "^$D $CMD .*--out $W/k.h5" | tail -1 || true)
    [ -n "$victim" ] && kill -9 "$victim"
    ( sleep 60; pkill -9 -f -- "--out $W/k.h5" ) &  # a job that hangs instead of ending is killed (and fails below)
    watchdog=$!
    wait "$job" 2>/dev/null || true
    kill "$watchdog" 2>/dev/null || true
  else
    pkill -9 -f -- "--out $W/k.h5" || true
    wait "$job" 2>/dev/null || true
  fi
  while pgrep -f -- "--out $W/k.h5" > /dev/null; do sleep 0.05; done
  # a run that got to write its end time was not interrupted
  killed_complete=0
  h5dump -a /end_time "$W/k.h5" > /dev/null 2>&1 && killed_complete=1
  echo "trial $trial: killed"
  # resume with another rank count (1 after the first kill, 3 after the second, 2 after the third)
  case "$trial" in
    1) "$D" "$CMD" "$CFG" "${OVR[@]}" --out "$W/k.h5" --resume > "$W/k2.log" ;;
    2) mpirun -np 3 "$D" "$CMD" "$CFG" "${OVR[@]}" --out "$W/k.h5" --resume > "$W/k2.log" ;;
    3) mpirun -np 2 "$D" "$CMD" "$CFG" "${OVR[@]}" --out "$W/k.h5" --resume > "$W/k2.log" ;;
  esac
  # the kill must have interrupted the run (not landed after its end)
  if [ "$killed_complete" = 1 ]; then
    echo "trial $trial: the kill did not interrupt the run; log:"; cat "$W/k2.log"; exit 1
  fi
  grep -E "resum|damaged" "$W/k2.log" || echo "trial $trial: killed before the first checkpoint, started over"
  "$D" compare "$W/r1.h5" "$W/k.h5"
done
echo "3 passed, 0 failed"
