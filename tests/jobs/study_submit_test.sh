#!/usr/bin/env bash
# `divcoll study --submit slurm` on a real Slurm (the private single-node cluster of slurm_test.sh,
# tests/jobs/slurm-cluster.sh): configs/studies/tiny.toml with longer agents (2 variants x 2 seeds, the
# second variant reusing the first's agents and connectors) as one array, 2 tasks at a time, 1 rank each.
# Checks: the dry run's jobs and dependencies; a derived run starts only after its base has ended (the
# tasks' recorded start and end times) and never more than 2 tasks run at once; one task gets the
# time-limit warning, stops after a checkpoint and requeues itself, and its continuation completes the run;
# the report job writes the robustness page; the 4 run files equal those of the same study run by
# `divcoll study` in one mpirun; --status on a half-finished study (done, waiting on its base, failed with
# its log's last lines, running); --adopt of a matching and of a mismatching run file (exit 2, nothing
# written); a grown study file continues the folder (only the new runs are submitted), a changed one is
# refused. Usage: study_submit_test.sh DIVCOLL SOURCE_DIR. Exit 77 (skipped) when Slurm is missing.
set -euo pipefail
D=$1 SRC=$2
t_start=$SECONDS
# every wait ends by this deadline, inside ctest's TIMEOUT (660 s); the waits are bounds for a hung job
deadline=$((SECONDS + ${SLURM_TEST_BUDGET_S:-570}))
skip() {
  echo "study submit test SKIPPED: $*"
  exit 77
}
fail() {
  echo "study submit test FAILED: $*"
  for f in "$W"/s/jobs/*.out "$W"/*.log "$W/log/slurmctld.log"; do
    [ -f "$f" ] && { echo "---- $f (last 60 lines)"; tail -60 "$f"; }
  done
  exit 1
}
# shellcheck source=tests/jobs/slurm-cluster.sh
source "$SRC/tests/jobs/slurm-cluster.sh"
slurm_cluster_need
W=$(mktemp -d)
trap slurm_cluster_down EXIT
trap 'exit 1' TERM INT HUP
# a requeued job starts again once its credential has expired: 10 s here instead of 120
SLURM_CLUSTER_AUTHINFO=cred_expire=10 slurm_cluster_up "$W"
cd "$W"

# the study: tiny.toml's study with agents long enough to be warned in (about 10 s a base run)
sed -e "s|base = \"../tiny.toml\"|base = \"$SRC/configs/tiny.toml\"|" \
  -e "s|^    'connectors.kinds=\[\"weak_uniform\",\"weak_diverse\"\]',|&\n    'agents.population=10', 'agents.generations=30', 'agents.epochs=5', 'agents.episode_steps=1000',|" \
  "$SRC/configs/studies/tiny.toml" > "$W/study.toml"
grep -q "agents.generations=30" "$W/study.toml" || fail "could not make the test study file"

echo "== reference: the study in one mpirun, 2 ranks"
(
  # shellcheck source=jobs/mpi-env.sh
  source "$SRC/jobs/mpi-env.sh"
  timeout "$((deadline - SECONDS))" mpirun -np 2 "$D" study "$W/study.toml" --out "$W/ref" > "$W/ref.log" 2>&1
) || fail "the reference study failed"
echo "reference done at $((SECONDS - t_start)) s"

echo "== dry run"
"$D" study "$W/study.toml" --out "$W/s" --submit slurm --ranks-per-run 1 --max-parallel 2 --dry-run -- --time=10 \
  > "$W/dry.log" 2>&1 || fail "the dry run failed"
cat "$W/dry.log"
[ ! -e "$W/s" ] || fail "the dry run wrote the study folder"
grep -q -- "--hold --array=1,2,3,4%2 --ntasks=1" "$W/dry.log" || fail "the dry run has no held array of 4 tasks, 2 at a time"
grep -q "scontrol update JobId=<A>_2 Dependency=afterok:<A>_1$" "$W/dry.log" || fail "run 2 does not wait for run 1"
grep -q "scontrol update JobId=<A>_4 Dependency=afterok:<A>_3$" "$W/dry.log" || fail "run 4 does not wait for run 3"
grep -q "dependency=afterany:<A> .*DIVCOLL_STUDY_REPORT=1" "$W/dry.log" || fail "no report job after the array"

echo "== submit"
export DIVCOLL_PROFILE=generic-cluster DIVCOLL_MAX_RESUBMITS=1 DIVCOLL_STOP_GRACE_S=60
"$D" study "$W/study.toml" --out "$W/s" --submit slurm --ranks-per-run 1 --max-parallel 2 -- --time=10 \
  > "$W/submit.log" 2>&1 || fail "the submission failed: $(cat "$W/submit.log")"
cat "$W/submit.log"
A=$(sed -n 's/^  \([0-9]*\)_1 .*/\1/p' "$W/submit.log")
R=$(sed -n 's/^  \([0-9]*\) *divcoll report.*/\1/p' "$W/submit.log")
{ [ -n "$A" ] && [ -n "$R" ]; } || fail "no array or report job id in the submission's output"
# submitting again while the jobs are queued is refused
if "$D" study "$W/study.toml" --out "$W/s" --submit slurm > "$W/again.log" 2>&1; then fail "a second submission was accepted"; fi
grep -q "still has job ${A}_1 in the queue" "$W/again.log" || fail "the second submission: $(cat "$W/again.log")"

# the time-limit warning (as --signal=B:USR1@120 sends it) to task 1 once its run has a checkpoint
end=$(by 180)
until [ -f "$W/s/baseline/seed1.h5.ckpt" ]; do
  [ "$SECONDS" -lt "$end" ] || fail "no checkpoint of run 1 after $((SECONDS - t_start)) s"
  sleep 0.1
done
scancel --batch --signal=USR1 "${A}_1"
echo "task ${A}_1: time-limit warning sent after its first checkpoint"
# --status while the study runs: every run listed, something running
seen_running=0
end=$(by 360)
while [ -n "$(squeue -h -j "$R" -o %i 2> /dev/null)" ]; do
  [ "$SECONDS" -lt "$end" ] || fail "the study's jobs did not end in time: $(squeue -h)"
  "$D" study "$W/s" --status > "$W/status.log" 2>&1 || true
  grep -q "^  [0-9] .*: running (job ${A}_[0-9]) at stage" "$W/status.log" && seen_running=1
  sleep 1
done
[ "$seen_running" = 1 ] || fail "--status never showed a running job"
echo "all jobs ended at $((SECONDS - t_start)) s"

echo "== checks"
for k in 1 2 3 4; do
  info=$(scontrol show job -o "${A}_$k")
  state=$(grep -o ' JobState=[^ ]*' <<< "$info")$(grep -o ' ExitCode=[^ ]*' <<< "$info")
  [ "$state" = " JobState=COMPLETED ExitCode=0:0" ] || fail "task $k:$state"
done
log1=$(ls "$W"/s/jobs/divcoll-*-"${A}_1.out")
grep -q "stopping the run after its next checkpoint" "$log1" || fail "task 1 did not act on the warning"
grep -q "checkpoint written: the run stopped right after it" "$log1" || fail "task 1 did not stop at a checkpoint"
grep -q "requeueing job ${A}_1 (requeue 1 of at most 1)" "$log1" || fail "task 1 did not requeue itself"
grep -q "Requeuing JobId=${A}_1" "$W/log/slurmctld.log" || fail "Slurm did not requeue task 1"
grep -q "job ${A}_1 (.*) on .*, requeue 1 of at most 1" "$log1" || fail "task 1 was not started again"
grep -q "resuming" "$log1" || fail "task 1's continuation did not resume the run"
grep -q "run complete: baseline/seed1.h5" "$log1" || fail "task 1's continuation did not complete the run"
# dependencies: each derived run started after its base's last end; never more than 2 tasks at once
times() { sed -n "s/^$2=//p" "$W/s/${1%.h5}.job"; }
for pair in "long_deploy/seed1 baseline/seed1" "long_deploy/seed2 baseline/seed2"; do
  read -r v b <<< "$pair"
  first=$(times "$v" started | head -1) last=$(times "$b" ended | tail -1)
  awk -v a="$first" -v b="$last" 'BEGIN { exit !(a >= b) }' || fail "$v started at $first, before $b ended at $last"
  echo "$v started $(awk -v a="$first" -v b="$last" 'BEGIN { printf "%.2f", a - b }') s after $b ended"
done
for r in baseline/seed1 long_deploy/seed1 baseline/seed2 long_deploy/seed2; do
  paste -d' ' <(times "$r" started) <(times "$r" ended)
done | awk '{ ev[NR*2] = $1 " 1"; ev[NR*2+1] = $2 " -1" } END { for (i in ev) print ev[i] }' | sort -g -k1,1 -k2,2n |
  awk '{ n += $2; if (n > m) m = n } END { print m }' > "$W/overlap"
[ "$(cat "$W/overlap")" -le 2 ] || fail "$(cat "$W/overlap") tasks ran at once (--max-parallel 2)"
echo "at most $(cat "$W/overlap") tasks at once"
for f in baseline/seed1.h5 long_deploy/seed1.h5 baseline/seed2.h5 long_deploy/seed2.h5; do
  "$D" compare "$W/ref/$f" "$W/s/$f" > /dev/null || fail "$f differs from the study run in one mpirun"
done
echo "4 run files identical to the one-mpirun study"
[ "$(grep -c "status = 'complete'" "$W/s/study.toml")" = 4 ] || fail "the manifest does not list 4 complete runs"
rlog=$(ls "$W"/s/jobs/divcoll-*-report-"$R".out)
grep -q "the study is complete" "$rlog" || fail "the report job did not find the study complete"
grep -q "divcoll report .* ended with status 0" "$rlog" || fail "the report job failed"
[ -s "$W/s/baseline/seed1.summary.json" ] || fail "the report job wrote no run summaries"
echo "report job: $(grep -c . "$rlog") lines, summaries written"
# the same command on the finished study submits only the report
"$D" study "$W/study.toml" --out "$W/s" --submit slurm --dry-run > "$W/done.log" 2>&1 || fail "dry run on the done study"
grep -q "4 runs, 0 to compute (4 complete)" "$W/done.log" || fail "the finished study: $(cat "$W/done.log")"

echo "== --status on a half-finished study"
"$D" study "$W/study.toml" --out "$W/h" --resume --run 1 > "$W/h1.log" 2>&1 ||
  fail "--run 1 failed: $(cat "$W/h1.log")"
set +e; "$D" study "$W/study.toml" --out "$W/h" --resume --run 4 > "$W/h4.log" 2>&1; rc=$?; set -e
{ [ "$rc" = 3 ] && grep -q "reuses the stages before deploy of run baseline/seed2.h5, which is not complete yet" "$W/h4.log"; } ||
  fail "--run 4 before its base: exit $rc: $(cat "$W/h4.log")"
printf 'scheduler=slurm\njob=99_3\nlog=%s\nstate=failed\nrc=1\n' "$W/h/fake.out" > "$W/h/baseline/seed2.job"
printf 'line one\nsomething went wrong here\n' > "$W/h/fake.out"
"$D" study "$W/h" --status > "$W/hs.log" 2>&1 && fail "--status with a failed run exits 0"
cat "$W/hs.log"
grep -q "^  1 baseline/seed1.h5: done$" "$W/hs.log" || fail "--status: run 1 is not done"
grep -q "^  2 long_deploy/seed1.h5: not started, ETA " "$W/hs.log" || fail "--status: run 2"
grep -q "^  3 baseline/seed2.h5: failed (job 99_3), status 1, last lines of" "$W/hs.log" || fail "--status: run 3"
grep -q "| something went wrong here" "$W/hs.log" || fail "--status: the failed run's log"
grep -q "^  4 long_deploy/seed2.h5: waiting on baseline/seed2.h5$" "$W/hs.log" || fail "--status: run 4"
grep -q "^1 done, 0 running, 1 to run, 1 waiting on their base, 1 failed; overall ETA" "$W/hs.log" || fail "--status: the totals"

echo "== --adopt"
"$D" study "$W/study.toml" --out "$W/h" --adopt "$W/ref/baseline/seed2.h5" > "$W/adopt.log" 2>&1 ||
  fail "--adopt of a matching run file: $(cat "$W/adopt.log")"
cat "$W/adopt.log"
cmp -s "$W/ref/baseline/seed2.h5" "$W/h/baseline/seed2.h5" || fail "the adopted file is not a copy"
grep -q "adopted_from = '$W/ref/baseline/seed2.h5'" "$W/h/study.toml" || fail "the manifest does not record the adoption"
grep -q "git_commit = '" "$W/h/study.toml" || fail "the manifest does not record the adopted file's commit"
before=$(cd "$W/h" && find . -type f -printf '%p %s %T@\n' | sort | md5sum)
set +e; "$D" study "$W/study.toml" --out "$W/h" --adopt "$W/ref/long_deploy/seed1.h5" --variant baseline > "$W/adopt2.log" 2>&1; rc=$?; set -e
cat "$W/adopt2.log"
[ "$rc" = 2 ] || fail "--adopt of a mismatching run file: exit $rc"
grep -q "is not the study's run baseline/seed1.h5 (variant baseline, seed 1): its config differs first at deploy.episode_steps (200 -> 300)" "$W/adopt2.log" ||
  fail "the refusal does not name the first differing key"
[ "$before" = "$(cd "$W/h" && find . -type f -printf '%p %s %T@\n' | sort | md5sum)" ] || fail "a refused --adopt wrote something"

echo "== a grown study continues the folder; a changed one is refused"
sed 's/^seeds = \[1, 2\]/seeds = [1, 2, 3]/' "$W/study.toml" > "$W/grown.toml"
"$D" study "$W/grown.toml" --out "$W/s" --submit slurm --max-parallel 2 --dry-run > "$W/grown.log" 2>&1 ||
  fail "the grown study: $(cat "$W/grown.log")"
{ grep -q "6 runs, 2 to compute (4 complete)" "$W/grown.log" && grep -q "array=5,6%2" "$W/grown.log" &&
  grep -q "JobId=<A>_6 Dependency=afterok:<A>_5" "$W/grown.log"; } || fail "the grown study: $(cat "$W/grown.log")"
sed 's/set = \["deploy.episode_steps=300"\]/set = ["deploy.episode_steps=301"]/' "$W/study.toml" > "$W/changed.toml"
set +e; "$D" study "$W/changed.toml" --out "$W/s" --resume > "$W/changed.log" 2>&1; rc=$?; set -e
{ [ "$rc" = 2 ] && grep -q "changes the config of run long_deploy/seed1.h5, which $W/s holds: deploy.episode_steps (300 -> 301)" "$W/changed.log"; } ||
  fail "a changed study: exit $rc: $(cat "$W/changed.log")"
echo "study submit: passed in $((SECONDS - t_start)) s"
