#!/usr/bin/env bash
# The runs behind science_connector_optimisation.md: every connector optimiser on the paper-scale
# agents (AGENTS.h5 = `mpirun -np 2 divcoll run configs/paper.toml 'run.stages=["agents"]' --out AGENTS.h5`),
# at a reduced scale: 1 replicate x 16 pairs x 30 iterations x 1000 steps, validation batch 12 pairs, trained
# pairs evaluated on 24 pairs at 1000 and 3000 steps on flat (the machine's 2 cores were shared with other
# jobs: one Adam run took ~5 min). Weak uniform at stiffness 300 (where Adam loses
# travel along its own gradient), weak diverse at the default 5000 (where Adam peaks, then drifts).
# Usage: [RUNS="u300:adam ..."] science_connector_optimisation_run.sh DIVCOLL AGENTS.h5 OUTDIR LANE
# (LANE = 0 or 1: two processes, each every other run of the list)
# es8 is the antithetic evolution strategy (connectors.optimizer = es); pagmo2's cmaes (connectors.optimizer =
# cmaes) costs O(popsize · 1473³) per generation here, about 8 s of one core per connector and iteration.
set -euo pipefail
D=$1 AGENTS=$2 OUT=$3 LANE=${4:-0}
mkdir -p "$OUT"
common=(connectors.replicates=1 connectors.batch_pairs=16 connectors.iterations=30 connectors.validation_pairs=12
        connectors.keep_best=true)
declare -A opt=(
  [adam]=""
  [adam_cosine]="connectors.lr_schedule=cosine connectors.lr_final=0.1"
  [adam_window100]="connectors.bptt_window=100"
  [adam_smooth2]="connectors.grad_samples=2 connectors.grad_sigma=0.01"
  [es8]="connectors.optimizer=es connectors.es_popsize=8 connectors.es_sigma=0.01"
  [adam_window100_cosine]="connectors.bptt_window=100 connectors.lr_schedule=cosine connectors.lr_final=0.1"
  [passive]="connectors.iterations=0 connectors.init_out_gain=0"
)
declare -A kind=(
  [u300]="connectors.kinds=weak_uniform connectors.weak_stiffness=300"
  [d5000]="connectors.kinds=weak_diverse"
)
# most telling first: the plain baseline and the black-box control, then the gradient remedies (RUNS="kind:opt
# ..." runs a subset)
default_runs="u300:adam d5000:adam u300:es8 d5000:es8 u300:adam_window100 d5000:adam_window100 u300:adam_cosine
              d5000:adam_cosine u300:adam_smooth2 d5000:adam_smooth2 u300:passive d5000:passive
              u300:adam_window100_cosine d5000:adam_window100_cosine"
# shellcheck disable=SC2206
runs=(${RUNS:-$default_runs})
i=0
for run in "${runs[@]}"; do
  k=${run%%:*} o=${run##*:}
  if (( i++ % 2 == LANE )); then
    # shellcheck disable=SC2086
    nice -n 10 "$D" connector-opt "$AGENTS" "${common[@]}" ${kind[$k]} ${opt[$o]} --label "$o" \
      --eval-pairs 24 --eval-steps 1000,3000 --out "$OUT/${k}_$o" --force > "$OUT/${k}_$o.log" 2>&1
  fi
done
