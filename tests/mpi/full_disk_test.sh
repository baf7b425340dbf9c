#!/usr/bin/env bash
# A full disk: the run stops with a clear message and exit 2, keeps its last checkpoint, and once space is
# freed, --resume finishes it with datasets identical to an uninterrupted run. Needs a small tmpfs
# (root and mount permission); prints why and exits 77 (skipped) where it cannot mount one.
# Usage: full_disk_test.sh DIVCOLL SOURCE_DIR
set -uo pipefail
D=$1 SRC=$2
source "$SRC/jobs/mpi-env.sh"
W=$(mktemp -d)
M="$W/disk"
mkdir -p "$M"
cleanup() { umount "$M" 2>/dev/null; rm -rf "$W"; }
trap cleanup EXIT
if ! mount -t tmpfs -o size=400k tmpfs "$M" 2>"$W/mount.err"; then
  echo "SKIPPED: cannot mount a small tmpfs here: $(cat "$W/mount.err")"
  exit 77
fi
CFG="$SRC/configs/tiny.toml"
"$D" run "$CFG" --out "$W/ref.h5" > "$W/ref.log" || { echo "FAILED: the reference run failed"; exit 1; }

"$D" run "$CFG" --out "$M/r.h5" > "$W/full.log" 2>&1
rc=$?
echo "on a full disk: exit $rc"; grep -m1 "divcoll: error" "$W/full.log"
[ "$rc" = 2 ] || { echo "FAILED: expected exit 2 on a full disk"; cat "$W/full.log"; exit 1; }
grep -q "cannot write" "$W/full.log" || { echo "FAILED: the message does not say what could not be written"; exit 1; }
[ ! -e "$M/r.h5.ckpt.tmp" ] || { echo "FAILED: a half-written checkpoint copy was left behind"; exit 1; }

mount -o remount,size=64m "$M" || { echo "FAILED: cannot grow the tmpfs"; exit 1; }
"$D" run "$CFG" --out "$M/r.h5" --resume > "$W/resume.log" 2>&1 || { echo "FAILED: resume after freeing space"; cat "$W/resume.log"; exit 1; }
grep -E "resum|damaged" "$W/resume.log" | head -3
"$D" compare "$W/ref.h5" "$M/r.h5" || { echo "FAILED: the resumed run differs"; exit 1; }
echo "full disk: passed"
