#!/usr/bin/env bash
# Times README command 1 on a bare Debian 12 system: a debootstrap'd bookworm (minbase) in a scratch folder, given
# what a fresh machine of this kind already has (g++, make, cmake, git, python3), a clone of this checkout's HEAD,
# then `bash jobs/quickstart.sh` inside it under chroot, timed from start to end. Root, network to Debian's mirror.
#   bash .ci/bare_quickstart.sh [SCRATCH]     (default /tmp/divcoll-bare; removed first, left for inspection)
# Stop other heavy work first: the time is the machine's, not the command's alone.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
root="${1:-/tmp/divcoll-bare}"
mirror=http://deb.debian.org/debian
command -v debootstrap >/dev/null || apt-get install -y -q debootstrap >/dev/null
umount_all() { for d in dev/shm dev/pts dev sys proc; do umount "$root/$d" 2>/dev/null || true; done; }
umount_all
rm -rf "$root"
debootstrap --variant=minbase bookworm "$root" "$mirror" >/dev/null
trap umount_all EXIT
for d in proc sys dev dev/pts; do mount --bind "/$d" "$root/$d"; done
mount -t tmpfs tmpfs "$root/dev/shm"
cp /etc/resolv.conf "$root/etc/"
printf 'deb %s bookworm main\ndeb %s bookworm-updates main\ndeb http://deb.debian.org/debian-security bookworm-security main\n' \
  "$mirror" "$mirror" >"$root/etc/apt/sources.list"
chroot "$root" bash -c "apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
  g++ make cmake git python3 ca-certificates procps" >/dev/null
git clone -q "$repo" "$root/root/divcoll"
echo "bare_quickstart: $(git -C "$repo" rev-parse --short=12 HEAD) on $(nproc) cores, in $root"
# shellcheck disable=SC2016  # expanded inside the chroot
chroot "$root" bash -c 'cd /root/divcoll && export HOME=/root && s=$(date +%s); bash jobs/quickstart.sh;
  echo "bare_quickstart: command 1 took $(( $(date +%s) - s )) s"'
