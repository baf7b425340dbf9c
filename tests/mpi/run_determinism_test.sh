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
# every rank must make the same HDF5 calls on the run file, reads included: checked at every checkpoint
# (io/h5.hpp Journal; a mismatch stops the run with each rank's calls)
export DIVCOLL_DEBUG_SYMMETRIC_IO=1
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT

echo "== uninterrupted with 1, 2, 3 ranks"
# a progress line every round (run.progress_every_s=0): the kills below are placed by these lines, not by time
"$D" "$CMD" "$CFG" "${OVR[@]}" run.progress_every_s=0 --out "$W/r1.h5" > "$W/r1.log"
mpirun -np 2 "$D" "$CMD" "$CFG" "${OVR[@]}" run.progress_every_s=0 --out "$W/r2.h5" > "$W/r2.log" 2>&1
N=$(wc -l < "$W/r2.log")
mpirun -np 3 "$D" "$CMD" "$CFG" "${OVR[@]}" run.progress_every_s=0 --out "$W/r3.h5" > "$W/r3.log"
"$D" compare "$W/r1.h5" "$W/r2.h5"
"$D" compare "$W/r1.h5" "$W/r3.h5"

echo "== killed and resumed"
for trial in 1 2 3; do
  # kill at a random point between 30% and 80% of the uninterrupted 2-rank run's progress lines (its log has N).
  # The freeze lands a few lines after the aimed one (the watcher's poll and pkill take tens of ms, a tiny round
  # less): a kill that lands after the run's end tests nothing, so that attempt is made again aiming at half the
  # line, at most 4 times (the last aims at line 1 or 2)
  L=$((N * 3 / 10 + RANDOM % (N / 2 + 1)))
  for attempt in 1 2 3 4; do
    rm -f "$W/k.h5" "$W/k.h5.ckpt"
    # start with 2 ranks; the output path is unique, so it names every process of the job
    mpirun -np 2 "$D" "$CMD" "$CFG" "${OVR[@]}" run.progress_every_s=0 --out "$W/k.h5" > "$W/k.log" 2>&1 &
    job=$!
    # the moment line L appears, every process of the job is frozen (SIGSTOP), so the kill lands there however
    # fast or slow the machine is; then every process at once (mpirun and the ranks, which Open MPI puts in
    # process groups of their own) is killed
    for _ in $(seq 6000); do  # at most about 120 s
      [ "$(wc -l < "$W/k.log")" -ge "$L" ] && break
      kill -0 "$job" 2> /dev/null || break
      sleep 0.02
    done
    pkill -STOP -f -- "--out $W/k.h5" || true
    echo "trial $trial: frozen at log line $(wc -l < "$W/k.log") of $N (aimed at $L)"
    if [ "$trial" = 3 ]; then
      # one rank only (not mpirun): Open MPI must notice and end the others
      victim=$(pgrep -f -- "^$D $CMD .*--out $W/k.h5" | tail -1 || true)
      [ -n "$victim" ] && kill -9 "$victim"
      pkill -CONT -f -- "--out $W/k.h5" || true
      # a job that hangs instead of ending is killed after 60 s (and fails below). A loop, not a background
      # `( sleep 60; pkill ... ) &` killed afterwards: a subshell killed before it has reset its traps runs this
      # script's EXIT trap, which removed $W (seen when the job had already ended)
      for _ in $(seq 1200); do
        kill -0 "$job" 2> /dev/null || break
        sleep 0.05
      done
      pkill -9 -f -- "--out $W/k.h5" || true
      wait "$job" 2>/dev/null || true
    else
      pkill -9 -f -- "--out $W/k.h5" || true
      wait "$job" 2>/dev/null || true
    fi
    while pgrep -f -- "--out $W/k.h5" > /dev/null; do sleep 0.05; done
    # a run that got to write its end time was not interrupted
    killed_complete=0
    h5dump -a /end_time "$W/k.h5" > /dev/null 2>&1 && killed_complete=1
    [ "$killed_complete" = 0 ] && break
    L=$(( (L + 1) / 2 ))
    [ "$attempt" -lt 4 ] && echo "trial $trial: the freeze landed after the run's end; again, aiming at line $L"
  done
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
