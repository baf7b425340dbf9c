#!/usr/bin/env bash
# Faults, end to end: no hang at any rank count, one writer per run file, a killed launcher, clean stops
# on signals, bad outputs. Usage: reliability_test.sh DIVCOLL SOURCE_DIR CASE
# Every command is bounded with `timeout`; every process started is ended by the EXIT trap (found by the
# test's own unique folder in its command line). No verdict depends on timing: where a process must be
# caught mid-run it is frozen (SIGSTOP) first, and waits only poll for a file to appear.
set -uo pipefail
D=$1 SRC=$2 CASE=$3
source "$SRC/jobs/mpi-env.sh"
W=$(mktemp -d /tmp/divcoll_reliab.XXXXXX)
CFG="$SRC/configs/tiny.toml"
# a longer agents stage (several seconds, a checkpoint per generation)
EVO=(agents.population=10 agents.generations=8 agents.epochs=5 agents.episode_steps=600 run.progress_every_s=0)
cleanup() {
  pkill -9 -f -- "$W/" 2> /dev/null
  chattr -i "$W"/* 2> /dev/null
  rm -rf "$W"
}
trap cleanup EXIT
fail() {
  echo "FAILED: $*"
  exit 1
}
# waits (at most 120 s) for a file to exist
await() {
  for _ in $(seq 1200); do
    [ -e "$1" ] && return 0
    sleep 0.1
  done
  fail "$1 never appeared"
}
# runs a command with a time bound; sets rc and out (stdout + stderr)
try() {
  out=$(timeout 120 "$@" 2>&1)
  rc=$?
  [ "$rc" != 124 ] || fail "timed out (a hang): $*"
}
expect() {  # expect CODE TEXT: the last `try` exited with CODE and said TEXT
  [ "$rc" = "$1" ] || fail "expected exit $1, got $rc: $out"
  grep -qF -- "$2" <<< "$out" || fail "expected the message to contain '$2': $out"
  echo "  exit $rc: $(grep -m1 -F -- "$2" <<< "$out")"
}
pids_of() { pgrep -f -- "^$D .*--out $1( |$)"; }

case $CASE in
missing_inputs)
  # a stage without its inputs is refused before any work, on every rank, at 1, 2 and 3 ranks
  for np in 1 2 3; do
    try mpirun -np "$np" "$D" run "$CFG" 'run.stages=["deploy"]' --out "$W/x.h5"
    expect 2 "stage deploy reads the results of stage agents"
    [ ! -e "$W/x.h5" ] && [ ! -e "$W/x.h5.lock" ] && [ ! -e "$W/x.h5.ckpt" ] || fail "np $np wrote files: $(ls "$W")"
  done
  try mpirun -np 2 "$D" run "$CFG" 'run.stages=["agents","analysis"]' --out "$W/x.h5"
  expect 2 "stage analysis reads the results of stage connectors"
  ;;
error_on_one_rank)
  # an error on rank 0 alone, after work started (rank 1 waits in a broadcast), ends every rank at once
  try "$D" run "$CFG" 'run.stages=["agents","connectors"]' --out "$W/a.h5"
  [ "$rc" = 0 ] || fail "the agents run failed: $out"
  /usr/bin/python3 -c "import h5py; f = h5py.File('$W/a.h5', 'a'); del f['agents/final/fitness']" || fail "h5py"
  try mpirun -np 2 "$D" run "$CFG" 'run.stages=["agents","connectors","deploy"]' --out "$W/a.h5" --resume
  expect 2 "missing dataset agents/final/fitness"
  ;;
one_writer)
  try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/ref.h5"
  [ "$rc" = 0 ] || fail "reference run: $out"
  "$D" evolve "$CFG" "${EVO[@]}" --out "$W/r.h5" > "$W/first.log" 2>&1 &
  first=$!
  await "$W/r.h5.ckpt"
  kill -STOP "$first"  # frozen mid-run, holding its lock
  before=$(md5sum < "$W/r.h5.ckpt")
  for flag in --resume --force; do
    try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/r.h5" "$flag"
    expect 2 "is being written by another run (host $(hostname), pid $first, started"
  done
  try mpirun -np 2 "$D" evolve "$CFG" "${EVO[@]}" --out "$W/r.h5" --resume
  expect 2 "is being written by another run (host $(hostname), pid $first"
  [ "$(md5sum < "$W/r.h5.ckpt")" = "$before" ] || fail "a refused run touched the checkpoint"
  # the holder dies: its lock is stale, and the next run takes it over and finishes the run
  kill -9 "$first"
  wait "$first" 2> /dev/null
  [ -e "$W/r.h5.lock" ] || fail "expected the dead run's lock file to be left behind"
  try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/r.h5" --resume
  expect 0 "stale lock $W/r.h5.lock (host $(hostname), pid $first"
  [ ! -e "$W/r.h5.lock" ] || fail "the lock file outlived the run"
  "$D" compare "$W/ref.h5" "$W/r.h5" || fail "the resumed run differs"
  ;;
kill_launcher)
  try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/ref.h5"
  [ "$rc" = 0 ] || fail "reference run: $out"
  # (a) the ranks outlive their killed mpirun (frozen here): a resume is refused while they live
  mpirun -np 2 "$D" evolve "$CFG" "${EVO[@]}" --out "$W/k.h5" > "$W/k.log" 2>&1 &
  job=$!
  await "$W/k.h5.ckpt"
  ranks=$(pids_of "$W/k.h5" | tr '\n' ' ')
  [ -n "$ranks" ] || fail "no ranks found"
  kill -STOP $ranks
  kill -9 "$job"
  wait "$job" 2> /dev/null
  # Open MPI's runtime may itself kill the orphaned (even frozen) ranks at any moment after mpirun is gone, so
  # either outcome is right: refused while the first rank lives, or its lock is found stale and the run resumed
  try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/k.h5" --resume
  if [ "$rc" = 0 ]; then
    grep -q "stale lock $W/k.h5.lock" <<< "$out" || fail "(a) resumed without taking over the stale lock: $out"
    echo "  (a) the runtime ended the orphaned ranks first; the stale lock was taken over"
    kill -9 $ranks 2> /dev/null
  else
    [ "$rc" = 2 ] || fail "(a) expected exit 2 (refused) or 0 (stale lock taken over), got $rc: $out"
    grep -q "is being written by\|is still being written by" <<< "$out" || fail "(a) the refusal names no writer: $out"
    echo "  exit $rc: $(grep -m1 "being written by" <<< "$out")"
    "$D" compare "$W/k.h5.ckpt" "$W/k.h5.ckpt" > /dev/null || fail "the checkpoint does not read back"
    kill -9 $ranks 2> /dev/null
    while [ -n "$(pids_of "$W/k.h5")" ]; do sleep 0.05; done
    try mpirun -np 3 "$D" evolve "$CFG" "${EVO[@]}" --out "$W/k.h5" --resume
    [ "$rc" = 0 ] || fail "resume after the ranks died: $out"
  fi
  "$D" compare "$W/ref.h5" "$W/k.h5" || fail "(a) the resumed run differs"
  # (b) the same with the ranks left running: resume at once, again until the old ranks are gone
  rm -f "$W/k.h5" "$W/k.h5.ckpt"
  mpirun -np 2 "$D" evolve "$CFG" "${EVO[@]}" --out "$W/k.h5" > "$W/k.log" 2>&1 &
  job=$!
  await "$W/k.h5.ckpt"
  kill -9 "$job"
  refused=0
  for _ in $(seq 120); do
    try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/k.h5" --resume
    grep -q "is being written by\|is still being written by" <<< "$out" || break
    refused=$((refused + 1))
    sleep 0.5
  done
  [ "$rc" = 0 ] || fail "(b) the resume failed: $out"
  echo "  (b) refused $refused time(s) while the old ranks lived, then resumed"
  "$D" compare "$W/ref.h5" "$W/k.h5" || fail "(b) the resumed run differs"
  ;;
signals)
  try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/ref.h5"
  [ "$rc" = 0 ] || fail "reference run: $out"
  n=0
  for launch in "" "mpirun -np 2"; do
    for sig in TERM INT USR1; do
      # Open MPI's mpirun handles TERM and INT itself (it kills the ranks); it forwards USR1
      [ -n "$launch" ] && [ "$sig" != USR1 ] && continue
      n=$((n + 1))
      $launch "$D" evolve "$CFG" "${EVO[@]}" --out "$W/s$n.h5" > "$W/s.log" 2>&1 &
      job=$!
      await "$W/s$n.h5.ckpt"
      kill -"$sig" "$job"
      wait "$job"
      rc=$?
      out=$(cat "$W/s.log")
      expect 75 "stopped by SIG$sig right after a checkpoint"
      grep -q "SIG$sig: stopping after the next checkpoint" <<< "$out" || fail "no message on the signal: $out"
      [ ! -e "$W/s$n.h5.lock" ] || fail "the lock file outlived the stopped run"
      try mpirun -np 3 "$D" evolve "$CFG" "${EVO[@]}" --out "$W/s$n.h5" --resume
      [ "$rc" = 0 ] || fail "resume after SIG$sig: $out"
      "$D" compare "$W/ref.h5" "$W/s$n.h5" > /dev/null || fail "the run stopped by SIG$sig and resumed differs"
    done
  done
  # a second signal stops at once (both delivered together: frozen, signalled twice, thawed)
  "$D" evolve "$CFG" "${EVO[@]}" --out "$W/t.h5" > "$W/t.log" 2>&1 &
  job=$!
  await "$W/t.h5.ckpt"
  kill -STOP "$job"
  kill -TERM "$job"
  kill -INT "$job"
  kill -CONT "$job"
  wait "$job"
  rc=$?
  out=$(cat "$W/t.log")
  [ "$rc" = 130 ] || [ "$rc" = 143 ] || fail "a second signal: expected exit 130 or 143, got $rc: $out"
  expect "$rc" "again: stopping now; the last checkpoint is kept"
  try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/t.h5" --resume
  [ "$rc" = 0 ] || fail "resume after two signals: $out"
  "$D" compare "$W/ref.h5" "$W/t.h5" > /dev/null || fail "the run stopped twice and resumed differs"
  # no grace: the first signal stops at once
  "$D" evolve "$CFG" "${EVO[@]}" run.stop_grace_s=0 --out "$W/g.h5" > "$W/g.log" 2>&1 &
  job=$!
  await "$W/g.h5.ckpt"
  kill -TERM "$job"
  wait "$job"
  rc=$?
  out=$(cat "$W/g.log")
  expect 143 "run.stop_grace_s = 0: stopping now"
  ;;
checkpoint_interval)
  # output.checkpoint_interval_s longer than the run: the run file is copied to its checkpoint only when a new
  # run starts, at each stage's end and on a stop, and results never depend on where the copies fall
  ST=('run.stages=["agents","connectors"]' connectors.iterations=5 run.progress_every_s=0)
  try "$D" run "$CFG" "${ST[@]}" --out "$W/ref.h5"
  [ "$rc" = 0 ] || fail "reference run: $out"
  # (a) a job that exits in the connectors stage (placed by the program: after the state of its third iteration
  # was written) resumes from the checkpoint: with copies at every commit (interval 0) that is iteration 2, with
  # the long interval the agents stage's end
  for interval in 0 86400; do
    rm -f "$W/c.h5" "$W/c.h5.ckpt"
    try env DIVCOLL_DEBUG_EXIT_IN_COMMIT=connectors:3 mpirun -np 2 "$D" run "$CFG" "${ST[@]}" \
      output.checkpoint_interval_s=$interval --out "$W/c.h5"
    [ "$rc" != 0 ] && grep -q "debug: exit between the state and the counter" <<< "$out" || fail "no exit at connectors:3 ($rc): $out"
    try "$D" run "$CFG" "${ST[@]}" output.checkpoint_interval_s=$interval --out "$W/c.h5" --resume
    [ "$rc" = 0 ] || fail "resume (interval $interval): $out"
    grep -q "stage agents: complete in the run file" <<< "$out" || fail "interval $interval: the agents stage was redone: $out"
    if [ "$interval" = 0 ]; then
      grep -q "connectors: resuming after iteration 2" <<< "$out" || fail "interval 0: not resumed after iteration 2: $out"
    else
      ! grep -q "connectors: resuming after" <<< "$out" || fail "interval $interval: resumed inside the connectors stage: $out"
    fi
    "$D" compare "$W/ref.h5" "$W/c.h5" > /dev/null || fail "interval $interval: the resumed run differs"
    echo "  interval $interval: $(grep -m1 "connectors: resuming after" <<< "$out" || echo "connectors from the start")"
  done
  # (b) a stop copies at the next commit whatever the interval: the checkpoint then holds the stopped run
  try "$D" evolve "$CFG" "${EVO[@]}" --out "$W/ref2.h5"
  [ "$rc" = 0 ] || fail "reference run: $out"
  mpirun -np 2 "$D" evolve "$CFG" "${EVO[@]}" output.checkpoint_interval_s=86400 --out "$W/s.h5" > "$W/s.log" 2>&1 &
  job=$!
  await "$W/s.h5.ckpt"
  kill -USR1 "$job"
  wait "$job"
  rc=$?
  out=$(cat "$W/s.log")
  expect 75 "stopped by SIGUSR1 right after a checkpoint"
  "$D" compare "$W/s.h5" "$W/s.h5.ckpt" > /dev/null || fail "the stop did not copy the run file to its checkpoint"
  try mpirun -np 3 "$D" evolve "$CFG" "${EVO[@]}" output.checkpoint_interval_s=86400 --out "$W/s.h5" --resume
  [ "$rc" = 0 ] || fail "resume after the stop: $out"
  "$D" compare "$W/ref2.h5" "$W/s.h5" > /dev/null || fail "the run stopped with a long interval and resumed differs"
  ;;
bad_outputs)
  S="$W/scene.h5"
  "$D" scene --kind pair --env flat --out "$S" > /dev/null || fail "scene"
  sum=$(md5sum < "$S")
  mkdir "$W/dir"
  try "$D" simulate --scene "$S" --steps 5 --out "$W/dir"
  expect 2 "is a directory"
  try "$D" simulate --scene "$S" --steps 5 --out /dev/null --force
  expect 2 "is not a regular file"
  [ -c /dev/null ] || fail "/dev/null is no longer a device"
  try "$D" simulate --scene "$S" --steps 5 --out "$S" --force
  expect 2 "is the input file"
  [ "$(md5sum < "$S")" = "$sum" ] || fail "the scene file was overwritten"
  try "$D" run "$CFG" --out "$W/dir"
  expect 2 "is a directory"
  try "$D" run "$CFG" --out /dev/null --force
  expect 2 "is not a regular file"
  [ -c /dev/null ] || fail "/dev/null is no longer a device"
  mkdir "$W/out"
  try "$D" run "$CFG" output.dir="$W/out" run.name=../escaped
  expect 2 "run.name = \"../escaped\" must be a plain file name"
  [ ! -e "$W/escaped.h5" ] || fail "the run escaped output.dir"
  : > "$W/empty.toml"
  try "$D" run "$W/empty.toml" --out "$W/e.h5"
  expect 2 "sets no key, so every key would take its paper-scale default"
  printf '# only a comment\n' > "$W/comment.toml"
  try "$D" run "$W/comment.toml" --out "$W/e.h5"
  expect 2 "sets no key"
  [ ! -e "$W/e.h5" ] || fail "an empty config started a run"
  # an immutable run file: the system's reason, not "truncated or damaged?"
  try "$D" run "$CFG" 'run.stages=["agents"]' --out "$W/i.h5"
  [ "$rc" = 0 ] || fail "run: $out"
  if chattr +i "$W/i.h5" 2> /dev/null; then
    try "$D" run "$CFG" 'run.stages=["agents"]' --out "$W/i.h5" --resume
    expect 2 "cannot open it for writing: Operation not permitted (is it immutable?"
    grep -q "truncated or damaged" <<< "$out" && fail "an immutable file was called damaged: $out"
    try "$D" run "$CFG" 'run.stages=["agents"]' --out "$W/i.h5" --force
    expect 2 "cannot open it for writing: Operation not permitted"
    chattr -i "$W/i.h5"
  else
    echo "  (chattr +i is not supported here: the immutable case is not checked)"
  fi
  ;;
memory)
  # the tape is estimated before it is allocated: refused at once with the estimate and the limit
  S="$W/pair.h5"
  "$D" scene --kind pair --env flat --out "$S" > /dev/null || fail "scene"
  try timeout 30 "$D" simulate --scene "$S" --steps 10000000 --grad --out "$W/t.h5"
  expect 2 "for 10000000 steps with --grad needs about"
  grep -qF "more than the limit of" <<< "$out" || fail "no limit in the message: $out"
  cp "$S" "$W/light.h5"
  /usr/bin/python3 -c "import h5py; f = h5py.File('$W/light.h5', 'a'); f['masses/m'][...] = 1e-9" || fail "h5py"
  try timeout 30 "$D" simulate --scene "$W/light.h5" --steps 1000 --grad --out "$W/t.h5"
  expect 2 "substep(s) per step), more than the limit of"
  # an explicit limit, and the same episode under a generous one
  try "$D" simulate --scene "$S" --steps 200 --grad --out "$W/t.h5" --memory-limit-gb 0.001
  expect 2 "(--memory-limit-gb)"
  try "$D" simulate --scene "$S" --steps 200 --grad --out "$W/t.h5" --memory-limit-gb 1
  [ "$rc" = 0 ] || fail "a small episode under a 1 GB limit: $out"
  [ ! -e "$W/t2.h5" ] || fail "unexpected output"
  # the run: every rank's tape, before any work, at 1 and 2 ranks
  for np in 1 2; do
    try mpirun -np "$np" "$D" run "$CFG" agents.episode_steps=10000000 --out "$W/r.h5"
    expect 2 "each rank's episodes with gradients need about"
    try mpirun -np "$np" "$D" run "$CFG" 'run.stages=["agents","connectors"]' run.memory_limit_gb=0.001 --out "$W/r.h5"
    expect 2 "run.memory_limit_gb / $np rank(s) on this node"
    [ ! -e "$W/r.h5" ] || fail "a refused run wrote its file"
  done
  ;;
checked_values)
  # every dataset carries HDF5's Fletcher-32 checksum; stored inputs of the stages to run must be finite
  try mpirun -np 2 "$D" run "$CFG" 'run.stages=["agents","connectors"]' --out "$W/a.h5"
  [ "$rc" = 0 ] || fail "run: $out"
  [ "$(h5dump -p -H "$W/a.h5" | grep -c FLETCHER32)" -gt 0 ] || fail "no checksum filter on the datasets"
  cp "$W/a.h5" "$W/bytes.h5"
  cp "$W/a.h5" "$W/nan.h5"
  # (a) random bytes written over the stored weights, behind HDF5's back
  /usr/bin/python3 - "$W/bytes.h5" << 'PY' || fail "corrupting"
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    info = f["agents/final/params"].id.get_chunk_info(0)
with open(sys.argv[1], "r+b") as raw:
    raw.seek(info.byte_offset + 1000)
    raw.write(bytes(range(7, 71)))
PY
  try "$D" run "$CFG" 'run.stages=["agents","connectors","deploy"]' --out "$W/bytes.h5" --resume
  expect 2 "do not read back or fail their checksum (the first: agents/final/params"
  grep -qi "checksum" <<< "$out" || fail "the message does not name the checksum: $out"
  /usr/bin/python3 -c "import h5py; h5py.File('$W/bytes.h5', 'r')['agents/final/params'][...]" 2> /dev/null &&
    fail "h5py read the damaged dataset without complaint"
  # (b) a NaN written through HDF5 (a valid checksum): refused before the stage that reads it, at 2 ranks
  /usr/bin/python3 -c "import h5py; f = h5py.File('$W/nan.h5', 'a'); d = f['agents/final/params']; d[1, 5] = float('nan')" || fail "h5py"
  try mpirun -np 2 "$D" run "$CFG" 'run.stages=["agents","connectors","deploy"]' --out "$W/nan.h5" --resume
  expect 2 "agents/final/params holds 1 non-finite value(s)"
  ;;
*)
  fail "unknown case $CASE"
  ;;
esac
echo "$CASE: passed"
