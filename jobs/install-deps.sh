#!/usr/bin/env bash
# Installs what divcoll needs from Debian's packages, only what is missing (idempotent). Run as root.
#   bash jobs/install-deps.sh [--test] [--only build|report] [--log FILE]
# Without --test: the build and runtime packages (README command 1, jobs/quickstart.sh). With --test also what
# only the tests use (README command 2, jobs/test.sh): a private Slurm with munge, shellcheck, chromium,
# gdb (the job-script checks print every rank's stack if a run hangs), pip and venv (the offline
# `pip install ./postprocess` of the run-file readers), the AArch64 cross compiler and qemu-user (the engine built for
# AArch64 and run against this machine's: tests/cross/aarch64_engine.sh).
# --only build: what building and running `divcoll` needs; --only report: what only its report, figures and movies
# need (Python's numpy, h5py, matplotlib, scipy, xarray and ffmpeg). quickstart.sh installs the second while the
# first builds.
# apt's output goes to FILE when given (default: the terminal). dpkg unpacks without fsync (--force-unsafe-io): a
# machine that loses power mid-install reinstalls.
set -euo pipefail

BUILD=(
  build-essential cmake pkg-config git bc
  libopenmpi-dev openmpi-bin
  libhdf5-openmpi-dev hdf5-tools
  libeigen3-dev libboost-serialization-dev libpagmo-dev
  libgtest-dev
  libtomlplusplus-dev libcli11-dev
)
REPORT=(
  python3-h5py python3-numpy python3-matplotlib python3-scipy python3-xarray
  ffmpeg
)
TEST_ONLY=(
  python3-pip python3-venv python3-setuptools
  shellcheck slurmctld slurmd slurm-client munge
  chromium
  gdb
  g++-aarch64-linux-gnu qemu-user
)

test=0
only=""
log=/dev/stdout
while [ $# -gt 0 ]; do
  case "$1" in
    --test) test=1 ;;
    --only) only="${2:-}"; shift ;;
    --log) log="$2"; shift ;;
    *) echo "install-deps: unknown argument $1 (use --test, --only build|report, --log FILE)" >&2; exit 2 ;;
  esac
  shift
done
case "$only" in
  "") PACKAGES=("${BUILD[@]}" "${REPORT[@]}") ;;
  build) PACKAGES=("${BUILD[@]}") ;;
  report) PACKAGES=("${REPORT[@]}") ;;
  *) echo "install-deps: --only takes build or report (got '$only')" >&2; exit 2 ;;
esac
[ "$test" = 1 ] && PACKAGES+=("${TEST_ONLY[@]}")

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${#missing[@]} of ${#PACKAGES[@]} packages: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages and not root; run: sudo apt-get install ${missing[*]}" >&2
  exit 1
fi
# wait for another apt to finish
while fuser /var/lib/dpkg/lock-frontend >/dev/null 2>&1; do sleep 5; done
export DEBIAN_FRONTEND=noninteractive
if ! { apt-get update -q && apt-get install -y -q --no-install-recommends -o Dpkg::Options::=--force-unsafe-io "${missing[@]}"; } >>"$log" 2>&1; then
  echo "install-deps: apt-get failed; its output is in $log" >&2
  exit 1
fi
