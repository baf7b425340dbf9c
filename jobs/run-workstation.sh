#!/usr/bin/env bash
# Workstation launcher: the whole pipeline of one config on every core (mpirun -np `nproc`), resumable:
# run it again after a crash, a reboot or Ctrl-C and it continues the run file from its last checkpoint
# (`divcoll run --resume`; with no run file it starts one).
#   bash jobs/run-workstation.sh [CONFIG [OUT [section.key=value ...]]]
# CONFIG: default configs/paper.toml; OUT: default runs/<config name>.h5. Environment: DIVCOLL_RANKS
# (default `nproc`), DIVCOLL_PROFILE (workstation), DIVCOLL_BIN (build/divcoll, built if missing).
set -euo pipefail
DIVCOLL_ROOT=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=jobs/lib/resumable-run.sh
source "$DIVCOLL_ROOT/jobs/lib/resumable-run.sh"
divcoll_load_profile "${DIVCOLL_PROFILE:-workstation}"
DIVCOLL_BIN=${DIVCOLL_BIN:-$DIVCOLL_ROOT/build/divcoll}
if [ ! -x "$DIVCOLL_BIN" ]; then
  bash "$DIVCOLL_ROOT/jobs/build.sh"
fi

config=$(divcoll_config_path "${1:-configs/paper.toml}")
out=$(realpath -m "${2:-runs/$(basename "$config" .toml).h5}")
mkdir -p "$(dirname "$out")"
# nothing to continue in: a time-limit warning (SIGUSR1) is only logged; Ctrl-C stops the run, and running
# this again continues it
DIVCOLL_CAN_CONTINUE=0 DIVCOLL_NO_CONTINUE_WHY="a workstation run; run this script again to continue"
divcoll_run_resumable "$config" "$out" "${@:3}"
