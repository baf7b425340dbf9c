#!/usr/bin/env bash
# `divcoll study` on configs/studies/tiny.toml (2 variants x 2 seeds at the tiny preset, the second variant
# differs only in a deploy key): the runs that reuse earlier stages hold them bit for bit and did not
# recompute them, and equal a run made from scratch; a study killed (SIGKILL) while it runs and resumed with
# another rank count gives the same run files, even when the base config file was edited in between (the
# study reads the copy it started with); the robustness page lists every claim x variant cell; a bad
# study file is refused before any work. Usage: study_test.sh DIVCOLL SOURCE_DIR
set -euo pipefail
D=$1 SRC=$2
source "$SRC/jobs/mpi-env.sh"
STUDY=$SRC/configs/studies/tiny.toml
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
fail() { echo "FAILED: $*"; exit 1; }

echo "== the study on 2 ranks"
mpirun -np 2 "$D" study "$STUDY" --out "$W/a" > "$W/a.log" 2>&1 || { cat "$W/a.log"; fail "study exited non-zero"; }
grep -E "^study: run [0-9]+/4 " "$W/a.log"
[ "$(grep -c "status = 'complete'" "$W/a/study.toml")" = 4 ] || fail "the manifest does not list 4 complete runs"
for s in 1 2; do
  B=$W/a/baseline/seed$s.h5 V=$W/a/long_deploy/seed$s.h5
  [ -f "$B" ] && [ -f "$V" ] || fail "missing run files for seed $s"
  # reuse: the variant's file was derived from the baseline's, before deploy ...
  h5dump -a /derived_from "$V" | grep -q "baseline/seed$s.h5 (stages before deploy)" || fail "long_deploy seed $s was not derived from baseline seed $s"
  # ... its agents and connectors datasets are the baseline's bit for bit ...
  for g in /agents /connectors; do
    h5diff "$B" "$V" "$g" "$g" > /dev/null || fail "$g of long_deploy seed $s differs from baseline seed $s"
  done
  # ... and differ where they must (its own deploy stage, longer episodes)
  if h5diff -q "$B" "$V" /deploy/agents/travel_bl /deploy/agents/travel_bl > /dev/null 2>&1; then
    fail "long_deploy seed $s has the baseline's deploy travel: its deploy stage was not run"
  fi
done
# not recomputed: the run that made long_deploy seed 2 found agents and connectors complete and ran neither
awk '/run 4\/4 long_deploy seed 2/{on=1} on' "$W/a.log" > "$W/run4.log"
grep -q "stage agents: complete in the run file" "$W/run4.log" || fail "run 4 did not find its agents stage in the file"
grep -q "stage connectors: complete in the run file" "$W/run4.log" || fail "run 4 did not find its connectors stage in the file"
if grep -qE "^(agents|connectors): " "$W/run4.log"; then fail "run 4 recomputed agents or connectors"; fi
# and a reused run equals the same config run from scratch
"$D" run "$SRC/configs/tiny.toml" 'run.stages=["agents","connectors","deploy","analysis"]' \
  'connectors.kinds=["weak_uniform","weak_diverse"]' deploy.episode_steps=300 run.seed=2 --out "$W/scratch.h5" > /dev/null
"$D" compare "$W/scratch.h5" "$W/a/long_deploy/seed2.h5" || fail "the reused run differs from a run from scratch"
echo "reuse: ok"

echo "== killed and resumed"
# trial 1 runs a copy of the study whose base config is a copy of tiny.toml, edited between the kill and the
# resume: the resumed runs must read the config the study started with (the folder's base.toml)
mkdir -p "$W/s1"
cp "$SRC/configs/tiny.toml" "$W/s1/tiny.toml"
sed 's|base = "../tiny.toml"|base = "tiny.toml"|' "$STUDY" > "$W/s1/study.toml"
for trial in 1 2; do
  rm -rf "$W/k"
  st=$STUDY
  [ "$trial" = 1 ] && st=$W/s1/study.toml
  # trial 1 is killed while run 2 (derived from run 1) computes, trial 2 while run 3 (from scratch) does
  at=$((trial + 1))
  "$D" study "$st" --out "$W/k" > "$W/k.log" 2>&1 &
  job=$!
  for _ in $(seq 1 1200); do
    grep -q "^study: run $at/4" "$W/k.log" 2>/dev/null && break
    kill -0 "$job" 2>/dev/null || break
    sleep 0.05
  done
  sleep 0.3
  kill -9 "$job" 2>/dev/null || true
  wait "$job" 2>/dev/null || true
  if [ "$(grep -c "status = 'complete'" "$W/k/study.toml" 2>/dev/null || true)" = 4 ]; then
    fail "trial $trial: the kill did not interrupt the study"
  fi
  echo "trial $trial: killed during run $at"
  # refused without --resume, continued with it (another rank count)
  if "$D" study "$st" --out "$W/k" > "$W/k2.log" 2>&1; then fail "an existing study was continued without --resume"; fi
  grep -q "pass --resume" "$W/k2.log" || fail "the refusal does not say --resume"
  cmp -s "$W/k/base.toml" "$SRC/configs/tiny.toml" || fail "trial $trial: base.toml is not the config the study started with"
  # trial 1: the config file is edited (fewer deployed pairs) before the resume
  [ "$trial" = 1 ] && sed -i 's/^pairs = 4 /pairs = 3 /' "$W/s1/tiny.toml"
  mpirun -np 2 "$D" study "$st" --out "$W/k" --resume > "$W/k2.log" 2>&1 || { cat "$W/k2.log"; fail "resume failed"; }
  if [ "$trial" = 1 ]; then
    grep -q "has changed since the study started; its runs go on with the copy" "$W/k2.log" \
      || fail "trial 1: the resume does not say that the config file changed"
  fi
  for f in baseline/seed1.h5 baseline/seed2.h5 long_deploy/seed1.h5 long_deploy/seed2.h5; do
    "$D" compare "$W/a/$f" "$W/k/$f" > /dev/null || fail "trial $trial: $f differs after kill and resume"
  done
  echo "trial $trial: resumed, 4 run files identical"
done

echo "== the robustness page"
"$D" report "$W/a" --out "$W/page" > "$W/page.log" 2>&1 || { cat "$W/page.log"; fail "divcoll report DIR failed"; }
/usr/bin/python3 - "$SRC/postprocess" "$W/page/robustness.md" "$W/a" <<'EOF' || fail "the robustness page lacks cells"
import os, sys
sys.path.insert(0, sys.argv[1])
import h5py, numpy as np
from divcoll_post import robustness
from divcoll_post import verdicts as V
table = open(sys.argv[2]).read().split("## Claims × variants")[1].split("## Effects")[0]
header = [l for l in table.splitlines() if l.startswith("| claim |")][0]
cols = [c.strip() for c in header.strip().strip("|").split("|")][1:]
# each variant, then its runs read under the report-time protocols (tiny.toml records deploy.early_step)
want = [f"{v}{r}" for v in ["baseline", "long_deploy"] for r in ["", " · training_length", " · training_rate"]]
assert cols == want, cols
names = {f"**{c.id}** {c.text}": c for c in V.CLAIMS}
rows = {}
for line in table.splitlines():
    cells = [c.strip() for c in line.strip().strip("|").split("|")]
    if len(cells) == 1 + len(cols) and cells[0] in names:
        rows[cells[0]] = cells[1:]
missing = [t for t in names if t not in rows]
assert not missing, f"claims without a row: {missing}"
for t, cells in rows.items():
    for col, c in zip(cols, cells):
        # two seeds: every measured cell is "too few seeds", never a verdict; a reading re-evaluates only the
        # claims that read agents alone
        if "·" in col and not names[t].reads_alone:
            assert c == "as source", (t, col, c)
        else:
            assert c == "not measured" or c.endswith("**too few seeds**"), (t, col, c)
measured = sum(c.endswith("**too few seeds**") for cs in rows.values() for c in cs)
assert measured >= 2 * 12, f"only {measured} measured cells"
# the readings: agents alone at deploy.early_step, and the deployment travel scaled to the training length
path = os.path.join(sys.argv[3], "baseline/seed1.h5")
run = robustness.SummaryRun(robustness.write_summary(path))
cfg = run.config
with h5py.File(path, "r") as f:
    t, st = f["deploy/agents/travel_bl_early"][()], f["deploy/agents/status"][()]
    early = np.array([t[e][(st[e] == 0) & np.isfinite(t[e])].mean() for e in range(t.shape[0])])
np.testing.assert_allclose(run.reread("training_length").alone, early, rtol=1e-12)
np.testing.assert_allclose(run.reread("training_rate").alone,
                           run.alone * cfg["connectors"]["episode_steps"] / cfg["deploy"]["episode_steps"], rtol=1e-12)
assert not np.array_equal(early, run.alone)
print(f"{len(rows)} claims x {len(cols)} columns, {measured} cells measured; readings checked")
EOF
for v in baseline long_deploy baseline__training_length; do [ -s "$W/page/figures/fig2a_$v.png" ] || fail "no Fig. 2A for $v"; done
[ -s "$W/page/robustness.png" ] || fail "no summary figure"
# and the study's verdict page (the protocol over populations) beside it, in Markdown and HTML with the same table
for x in md html; do [ -s "$W/page/verdicts/verdicts.$x" ] || fail "divcoll report DIR wrote no verdicts.$x"; done
grep -q "(verdicts/verdicts.html)" "$W/page/robustness.md" || fail "the robustness page does not link the verdict page"
for c in C01 C28; do grep -q "<td>$c</td>" "$W/page/verdicts/verdicts.html" || fail "verdicts.html lacks the row of $c"; done

echo "== the folder kept as manifest and run summaries gives the same page, and counts as complete"
for v in baseline long_deploy; do
  for s in 1 2; do
    [ -s "$W/a/$v/seed$s.summary.json" ] || fail "divcoll report wrote no summary beside $v/seed$s.h5"
  done
done
"$D" report "$W/a" --out "$W/page_keep" --keep "$W/kept" > "$W/keep.log" 2>&1 || { cat "$W/keep.log"; fail "report --keep failed"; }
grep -q "4 run summaries" "$W/keep.log" || { cat "$W/keep.log"; fail "divcoll report --keep did not keep 4 summaries"; }
ls "$W/kept"/*/*.h5 > /dev/null 2>&1 && fail "--keep copied run files"
# --keep is for study folders: with a run file it is refused before anything is written
set +e; "$D" report "$W/a/baseline/seed1.h5" --out "$W/nopage" --keep "$W/kept_bad" > "$W/keep_bad.log" 2>&1; rc=$?; set -e
[ "$rc" = 2 ] && grep -q "is a run file" "$W/keep_bad.log" && [ ! -e "$W/kept_bad" ] && [ ! -e "$W/nopage" ] \
  || { cat "$W/keep_bad.log"; fail "report --keep of a run file: exit $rc"; }
"$D" report "$W/kept" --out "$W/page2" > "$W/page2.log" 2>&1 || { cat "$W/page2.log"; fail "divcoll report of the kept folder failed"; }
grep -q "4 run(s) read from their summaries" "$W/page2/robustness.md" || fail "the kept folder's page does not say it read summaries"
diff <(sed -n '/^## Claims/,$p' "$W/page/robustness.md") <(sed -n '/^## Claims/,$p' "$W/page2/robustness.md") \
  || fail "the page from summaries differs from the page from run files"
cmp "$W/page/figures/fig2a_baseline__training_length.png" "$W/page2/figures/fig2a_baseline__training_length.png" \
  || fail "Fig. 2A from summaries differs"
"$D" study "$STUDY" --out "$W/kept" --resume > "$W/kept.log" 2>&1 || { cat "$W/kept.log"; fail "resume of the kept folder failed"; }
[ "$(grep -c "complete in" "$W/kept.log")" = 4 ] || { cat "$W/kept.log"; fail "the kept runs were not all counted complete"; }
ls "$W/kept"/*/*.h5 > /dev/null 2>&1 && fail "the resume of the kept folder computed a run"
# a run to compute whose base run is kept only as a summary is refused with a message, not a missing-file error
rm "$W/kept/long_deploy/seed2.summary.json"
set +e; "$D" study "$STUDY" --out "$W/kept" --resume > "$W/kept2.log" 2>&1; rc=$?; set -e
[ "$rc" = 2 ] || { cat "$W/kept2.log"; fail "a run reusing a summary-only base: exit $rc, not 2"; }
grep -q "reuses the stages before deploy of baseline/seed2.h5, whose run file is not in" "$W/kept2.log" \
  || { cat "$W/kept2.log"; fail "no clear message for a summary-only base"; }
echo "summaries: ok"

echo "== bad study files are refused before any work"
sed 's/set = \["deploy.episode_steps=300"\]/set = ["deploy.episode_stepz=300"]/' "$STUDY" > "$W/bad1.toml"
sed 's/set = \["deploy.episode_steps=300"\]/set = ["deploy.episode_steps=0"]/' "$STUDY" > "$W/bad2.toml"
sed 's/^seeds = \[1, 2\]/seeds = [1, 2]\nrepeats = 3/' "$STUDY" > "$W/bad3.toml"
for b in 1 2 3; do
  sed -i "s|base = \"../tiny.toml\"|base = \"$SRC/configs/tiny.toml\"|" "$W/bad$b.toml"
  set +e; "$D" study "$W/bad$b.toml" --out "$W/bad$b" > "$W/bad.log" 2>&1; rc=$?; set -e
  [ "$rc" = 2 ] || { cat "$W/bad.log"; fail "bad study $b: exit $rc, not 2"; }
  [ ! -e "$W/bad$b" ] || fail "bad study $b wrote $W/bad$b"
  head -1 "$W/bad.log"
  [ "$b" = 3 ] || grep -q "variant long_deploy" "$W/bad.log" || fail "bad study $b: the message does not name the variant"
done
echo "== the reduced study file of the real question validates, and its plan reuses what it can"
"$D" study "$SRC/configs/studies/claims.toml" --out "$W/claims" --plan > "$W/plan.log" || { cat "$W/plan.log"; fail "claims.toml is refused"; }
[ ! -e "$W/claims" ] || fail "--plan wrote the study folder"
grep -q "= 65 runs" "$W/plan.log" || fail "claims.toml: not 13 variants x 5 seeds"
grep -q "training_length/seed3.h5: computes analysis, reuses baseline/seed3.h5" "$W/plan.log" || fail "an analysis-key variant does not reuse deploy"
grep -q "alone_runway_mean/seed1.h5: computes deploy,analysis, reuses baseline/seed1.h5" "$W/plan.log" || fail "a deploy-key variant does not reuse the connectors"
grep -q "weak_k1000/seed5.h5: computes connectors,deploy,analysis, reuses baseline/seed5.h5" "$W/plan.log" || fail "a connectors-key variant does not reuse the agents"
grep -q "weak_agents/seed2.h5: computes agents,connectors,deploy,analysis$" "$W/plan.log" || fail "an agents-key variant reuses something"
# run.precision changes every stage's numbers: its variant reuses nothing (it once reused all but the analysis)
"$D" study "$SRC/configs/studies/claims_reduced_precision.toml" --out "$W/precision" --plan > "$W/plan_p.log" \
  || { cat "$W/plan_p.log"; fail "claims_reduced_precision.toml is refused"; }
grep -q "float_networks/seed3.h5: computes agents,connectors,deploy,analysis$" "$W/plan_p.log" \
  || { cat "$W/plan_p.log"; fail "a run.precision variant reuses a stage computed in double"; }
# a variant that names its seeds runs only at those, after its seed's baseline, and reuses it
"$D" study "$SRC/configs/studies/verdicts.toml" --out "$W/verdicts" --plan > "$W/plan_v.log" \
  || { cat "$W/plan_v.log"; fail "verdicts.toml is refused"; }
grep -q "= 15 runs" "$W/plan_v.log" || { cat "$W/plan_v.log"; fail "verdicts.toml: not 10 baseline + 5 supplement runs"; }
grep -q "supplement/seed6.h5: computes specialists,scaling,graded, reuses baseline/seed6.h5" "$W/plan_v.log" \
  || { cat "$W/plan_v.log"; fail "the supplement variant does not reuse its seed's baseline"; }
! grep -q "supplement/seed1.h5" "$W/plan_v.log" || fail "the supplement variant runs at a seed it does not name"
sed 's/^seeds = \[6, 7, 8, 9, 10\]/seeds = [6, 11]/' "$SRC/configs/studies/verdicts.toml" > "$W/bad4.toml"
sed -i "s|base = \"../paper.toml\"|base = \"$SRC/configs/paper.toml\"|" "$W/bad4.toml"
set +e; "$D" study "$W/bad4.toml" --out "$W/bad4" --plan > "$W/bad4.log" 2>&1; rc=$?; set -e
[ "$rc" = 2 ] && grep -q "seed 11 is not one of study.seeds" "$W/bad4.log" || { cat "$W/bad4.log"; fail "a variant seed outside study.seeds: exit $rc"; }
echo "study: passed"
