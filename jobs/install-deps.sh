#!/usr/bin/env bash
# Installs what divcoll needs from Debian's packages, only what is missing (idempotent). Run as root.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git bc
  libopenmpi-dev openmpi-bin
  libhdf5-openmpi-dev hdf5-tools
  libeigen3-dev libboost-serialization-dev libpagmo-dev
  libgtest-dev
  libtomlplusplus-dev libcli11-dev
  python3-h5py python3-numpy python3-matplotlib python3-scipy
  shellcheck slurmctld slurmd slurm-client munge
)

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

echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages and not root; run: sudo apt-get install ${missing[*]}" >&2
  exit 1
fi
# wait for another apt to finish
while fuser /var/lib/dpkg/lock-frontend >/dev/null 2>&1; do sleep 5; done
export DEBIAN_FRONTEND=noninteractive
apt-get update -q
apt-get install -y -q --no-install-recommends "${missing[@]}"
